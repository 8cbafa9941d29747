"""Physical parameters of the robot plant, with defaults derived in docs/plant.md."""

import math
from dataclasses import dataclass, fields

from ..common.errors import ParameterError

__all__ = ["PlantParameters"]

# Names that must be strictly positive, and the one fraction that must lie in (0, 1].
_POSITIVE = (
    "mass", "yaw_inertia", "wheel_radius", "track_width", "wheel_inertia",
    "motor_resistance", "motor_inductance", "torque_constant", "back_emf_constant",
    "rotor_inertia", "gear_ratio", "speed_window", "mu", "slip_stiffness",
    "slip_speed_floor", "v_supply", "gravity", "max_substep", "substep_tolerance",
)


@dataclass
class PlantParameters:
    """Every number the robot plant needs, in SI units (angles in rad).

    The defaults describe the paper's robot (Table 11, Sec. 5) with two 12 V geared motors of
    the IG-32PGM 14:1 class, whose constants are derived in ``docs/plant.md``.

    Attributes
    ----------
    mass : float
        Robot mass [kg] (Table 11: 4.5).
    yaw_inertia : float
        Body moment of inertia about the vertical axis through the axle midpoint [kg m^2];
        0.075 is a uniform 0.28 m x 0.35 m slab of 4.5 kg (the paper's I = 2.5 is a misprint).
    wheel_radius, track_width : float
        Driven wheel radius and distance between the wheel contact points [m].
    wheel_inertia : float
        Inertia of one wheel with hub and gearbox output stage about its axle [kg m^2].
    motor_resistance, motor_inductance : float
        Armature resistance [Ohm] and inductance [H].
    torque_constant : float
        Motor torque per armature current [N m/A].
    back_emf_constant : float
        Back-EMF per motor shaft speed [V s/rad].
    motor_viscous_friction : float
        Viscous friction at the motor shaft [N m s/rad]; it carries the no-load current.
    rotor_inertia : float
        Motor rotor inertia [kg m^2].
    gear_ratio : float
        Motor revolutions per wheel revolution.
    gear_efficiency : float
        Fraction of motor-side torque that reaches the wheel, in (0, 1].
    encoder_ppr : int
        Encoder counts per wheel revolution (52 per motor revolution x 14 = 728).
    speed_window : float
        Period over which encoder counts are differenced into a wheel speed [s].
    mu : float
        Tyre-floor friction coefficient (peak of the friction circle).
    slip_stiffness : float
        Initial slope of traction force over slip, per newton of normal load.
    slip_speed_floor : float
        Smallest speed used to normalise slip, so slip stays defined at standstill [m/s].
    v_supply : float
        Battery voltage; input voltages are clamped to +-v_supply [V].
    gravity : float
        Gravitational acceleration [m/s^2].
    x0, y0, heading0 : float
        Start pose [m, m, rad]; heading counter-clockwise from +x.
    max_substep : float
        Longest internal integration step [s].
    substep_tolerance : float
        Largest linearisation defect of the tyre forces on one substep, expressed as the body
        speed change it would cause (``h |defect| / mass``) [m/s]; a substep that exceeds it
        is redone in up to 16 equal pieces.
    coulomb_friction : float
        Coulomb (dry) friction torque at the motor shaft [N m], against the shaft's rotation,
        regularised as ``T_c tanh(N w / COULOMB_SPEED)`` (:mod:`.dynamics`); 0 (default): none,
        the no-load current is carried by ``motor_viscous_friction`` alone (docs/plant.md).
    """

    mass: float = 4.5
    yaw_inertia: float = 0.075
    wheel_radius: float = 0.06
    track_width: float = 0.289
    wheel_inertia: float = 2.0e-4
    motor_resistance: float = 2.4
    motor_inductance: float = 2.4e-3
    torque_constant: float = 0.01808
    back_emf_constant: float = 0.01808
    motor_viscous_friction: float = 7.17e-6
    rotor_inertia: float = 3.0e-6
    gear_ratio: float = 14.0
    gear_efficiency: float = 0.8
    encoder_ppr: int = 728
    speed_window: float = 0.02
    mu: float = 0.8
    slip_stiffness: float = 10.0
    slip_speed_floor: float = 0.05
    v_supply: float = 11.1
    gravity: float = 9.81
    x0: float = 0.0
    y0: float = 0.0
    heading0: float = math.pi / 2
    max_substep: float = 2.0e-3
    substep_tolerance: float = 1.0e-4
    coulomb_friction: float = 0.0

    def validate(self):
        """Raise :class:`ParameterError` listing every invalid parameter at once."""
        problems = []
        for field in fields(self):
            value = getattr(self, field.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                problems.append(f"{field.name} = {value!r} is not a number")
            elif not math.isfinite(value):
                problems.append(f"{field.name} = {value!r} is not finite")
        if not problems:
            for name in _POSITIVE:
                value = getattr(self, name)
                if value <= 0.0:
                    problems.append(f"{name} = {value!r} must be > 0")
            if self.motor_viscous_friction < 0.0:
                problems.append(f"motor_viscous_friction = {self.motor_viscous_friction!r} "
                                "must be >= 0")
            if self.coulomb_friction < 0.0:
                problems.append(f"coulomb_friction = {self.coulomb_friction!r} must be >= 0")
            if not 0.0 < self.gear_efficiency <= 1.0:
                problems.append(f"gear_efficiency = {self.gear_efficiency!r} must be in (0, 1]")
            if int(self.encoder_ppr) != self.encoder_ppr or self.encoder_ppr < 1:
                problems.append(f"encoder_ppr = {self.encoder_ppr!r} must be an integer >= 1")
        if problems:
            raise ParameterError("RobotPlant parameters: " + "; ".join(problems))
        return self

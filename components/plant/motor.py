"""Geared DC motor relations: constants from datasheet figures and the analytic steady state."""

__all__ = ["MotorConstants", "motor_constants_from_datasheet", "steady_wheel_speed"]


class MotorConstants:
    """Armature constants of a brushed DC motor, in SI units.

    Attributes
    ----------
    resistance : float
        Armature resistance [Ohm].
    inductance : float
        Armature inductance [H].
    torque_constant : float
        [N m/A]; equal to ``back_emf_constant`` in SI units for an ideal machine.
    back_emf_constant : float
        [V s/rad].
    viscous_friction : float
        Shaft friction per shaft speed [N m s/rad] that carries the no-load current.
    """

    def __init__(self, resistance, inductance, torque_constant, back_emf_constant,
                 viscous_friction):
        self.resistance = resistance
        self.inductance = inductance
        self.torque_constant = torque_constant
        self.back_emf_constant = back_emf_constant
        self.viscous_friction = viscous_friction


def motor_constants_from_datasheet(rated_voltage, no_load_speed, no_load_current,
                                   stall_current, electrical_time_constant):
    """Derive armature constants from the figures a geared-motor datasheet prints.

    Parameters
    ----------
    rated_voltage : float
        Supply voltage the figures refer to [V].
    no_load_speed : float
        Motor shaft speed without load at ``rated_voltage`` [rad/s] (before the gearbox).
    no_load_current : float
        Armature current without load [A].
    stall_current : float
        Armature current with the shaft held [A].
    electrical_time_constant : float
        L/R [s].

    Returns
    -------
    MotorConstants

    Notes
    -----
    At stall there is no back-EMF, so ``R = V / I_stall``. Without load,
    ``V = R I0 + Ke w0``, so ``Ke = (V - R I0) / w0``; in SI units ``Kt = Ke``. The no-load
    current balances the shaft friction, modelled viscous: ``b = Kt I0 / w0``.
    """
    resistance = rated_voltage / stall_current
    back_emf_constant = (rated_voltage - resistance * no_load_current) / no_load_speed
    viscous_friction = back_emf_constant * no_load_current / no_load_speed
    return MotorConstants(resistance, resistance * electrical_time_constant,
                          back_emf_constant, back_emf_constant, viscous_friction)


def steady_wheel_speed(voltage, parameters):
    """Wheel speed [rad/s] at constant ``voltage`` when the tyre transmits no force.

    Parameters
    ----------
    voltage : float
        Armature voltage [V].
    parameters : PlantParameters

    Returns
    -------
    float

    Notes
    -----
    Driving straight (or on any steady circle without rolling resistance) the body does not
    accelerate, so the tyre force is zero and the motor only overcomes its own friction:
    ``Kt i = b N w`` and ``V = R i + Ke N w`` give ``w = V / (N (Ke + R b / Kt))``.
    The gear efficiency scales both terms and cancels.
    """
    p = parameters
    per_speed = p.gear_ratio * (p.back_emf_constant
                                + p.motor_resistance * p.motor_viscous_friction
                                / p.torque_constant)
    return voltage / per_speed


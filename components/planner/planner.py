"""The planner core: fixes in, held wheel-speed references out, in one of three modes."""

import math

from ..common.errors import InputError, ParameterError
from .curvature_mode import CurvatureMode
from .geometry import radius_of
from .limiter import limit_wheel_change
from .odometry import Odometry
from .odometry_check import OdometryCheck
from .pure_pursuit import PurePursuitMode
from .rotate_then_go import RotateThenGoMode

__all__ = ["TargetPlanner", "MODES", "IDLE", "MOVING", "STOPPING", "TURNING",
           "FIX_NONE", "FIX_ACCEPTED", "FIX_INVALID", "FIX_NEGATIVE", "FIX_REJECTED",
           "REACQUIRE_AFTER", "HOLD_SPEED_FACTOR", "WHEEL_CHECK_SPEED", "WHEEL_STUCK_SPEED",
           "WHEEL_RETRY", "ODOMETRY_RETRY", "BEARING_NOISE", "STOP_NONE", "STOP_WHEEL",
           "STOP_ODOMETRY"]

# After this many fixes in a row fail the gate, the next one is taken anyway: the target did
# move (a source that turns up elsewhere) rather than the localizer erring that often in a row.
REACQUIRE_AFTER = 5
# Without fixes for fix_timeout, the robot drives out its last arc at this fraction of the
# speed: the arc ends stop_distance short of the last heard target, so it cannot reach a
# source that stayed there, and a source that came closer has time to be heard again.
HOLD_SPEED_FACTOR = 0.5
# Wheel check: a wheel whose reference is at least WHEEL_CHECK_SPEED but whose encoder gives
# no count (measured speed below half a count per 20 ms window) for wheel_check_time is not
# turning as told or not measured (a frozen encoder, a stalled wheel). The robot then stops
# at once (references 0, no ramp: the wheel may be running away) for WHEEL_RETRY, then tries
# again. A healthy wheel at 0.1 m/s gives about 4 counts per window.
WHEEL_CHECK_SPEED = 0.1
WHEEL_STUCK_SPEED = 0.013
WHEEL_RETRY = 1.0
# Odometry check (OdometryCheck): when the fixes' bearings drift from what the odometry
# predicts, the robot stops at once (the wheel that the odometry misreads may be running at a
# multiple of its reference), stands for ODOMETRY_RETRY, then drives again on the fixes taken
# while standing. The same second as the wheel check: the body's mechanical time constant is
# 0.39 s (docs/plant.md), so after 1 s it is at rest and the standing fixes see the source alone.
ODOMETRY_RETRY = 1.0
# Largest bearing error of a fix the localizer lets through [rad], measured on every shipped
# scenario (docs/faults.md): 0.15 deg on fault-free fixes, 0.42 deg at 0 dB SNR; rounded up.
BEARING_NOISE = 0.01

# Why the references are held at 0 (the ``stop_reason`` output).
STOP_NONE, STOP_WHEEL, STOP_ODOMETRY = 0, 1, 2

MODES = {mode.name: mode for mode in (CurvatureMode, RotateThenGoMode, PurePursuitMode)}

# Values of the ``state`` output.
IDLE, MOVING, STOPPING, TURNING = 0, 1, 2, 3

# What :meth:`TargetPlanner.update` did with the fix inputs (``fix_outcome``).
FIX_NONE = "none"
FIX_ACCEPTED = "accepted"
FIX_INVALID = "invalid"
FIX_NEGATIVE = "negative"
FIX_REJECTED = "rejected"


class TargetPlanner:
    """Wheel-speed references that drive a two-wheeled robot to the latest heard target.

    Call :meth:`update` once per planner step with the inputs at that time; it returns the
    wheel speeds to hold until the next call. A fix is new when ``measurement_id`` changes (or
    on the first call); it is used only if ``valid`` is true and the distance is not negative.
    The target is kept in the odometry frame (the start pose: (0, 0) facing +y), which the
    planner integrates from the measured wheel speeds, so it stays put while the robot moves.

    Parameters
    ----------
    track_width : float
        Distance between the wheels [m], ``L`` of Eqs. (38)-(42).
    v_cruise : float
        Cruise speed of the robot's centre [m/s], ``V`` of Eqs. (41)-(42).
    v_max : float
        Largest wheel speed [m/s] (Eq. 43).
    a_max : float
        Largest wheel acceleration [m/s^2] (Eq. 44).
    stop_distance : float
        Straight-line distance [m] from the target at which the robot stops.
    mode : str
        ``"curvature"`` (the paper), ``"rotate_then_go"`` or ``"pure_pursuit"``.
    max_target_speed : float
        Plausibility gate [m/s], 0 disables it (the paper has none). A new fix whose target
        lies more than ``max_target_speed * dt + target_jump_margin`` from the last accepted
        target (``dt`` since that fix) implies a source faster than it can be and is
        rejected (``rejected_fixes`` counts them); after :data:`REACQUIRE_AFTER` rejections in
        a row the next fix is accepted.
    target_jump_margin : float
        Localization error allowed on top of the target's motion [m].
    fix_timeout : float
        Without an accepted fix for this long [s] the robot slows to
        :data:`HOLD_SPEED_FACTOR` of ``v_cruise`` (at ``a_max``), drives out its last arc and
        stops at its end; the next accepted fix restores full speed. 0 disables (the paper's
        robot drives out its last arc at full speed).
    wheel_check_time : float
        A wheel told to turn (|reference| >= :data:`WHEEL_CHECK_SPEED`) whose encoder shows no
        motion for this long [s] stops the robot for :data:`WHEEL_RETRY` (``wheel_faults``
        counts the trips); 0 disables.
    odometry_check : bool
        Compare each accepted fix's bearing with the odometry's prediction
        (:class:`.OdometryCheck`, needs ``max_target_speed`` > 0); when they disagree on
        several fixes in a row the robot stops at once for :data:`ODOMETRY_RETRY`
        (``odometry_faults`` counts the trips). Off by default (the paper has none).
    bearing_noise : float
        Largest bearing error of one fix [rad] for the odometry check.
    """

    def __init__(self, track_width=0.289, v_cruise=0.3, v_max=0.4, a_max=0.4,
                 stop_distance=0.5, mode="curvature", max_target_speed=0.0,
                 target_jump_margin=0.3, fix_timeout=0.0, wheel_check_time=0.0,
                 odometry_check=False, bearing_noise=BEARING_NOISE):
        if mode not in MODES:
            raise ParameterError(f"mode = {mode!r}: not one of {sorted(MODES)}")
        for name, value in (("track_width", track_width), ("v_cruise", v_cruise),
                            ("v_max", v_max), ("a_max", a_max)):
            if not (math.isfinite(value) and value > 0.0):
                raise ParameterError(f"{name} = {value!r}: must be a finite number > 0")
        if not (math.isfinite(stop_distance) and stop_distance >= 0.0):
            raise ParameterError(f"stop_distance = {stop_distance!r}: must be a finite number >= 0")
        for name, value in (("max_target_speed", max_target_speed),
                            ("target_jump_margin", target_jump_margin),
                            ("fix_timeout", fix_timeout),
                            ("wheel_check_time", wheel_check_time),
                            ("bearing_noise", bearing_noise)):
            if not (math.isfinite(value) and value >= 0.0):
                raise ParameterError(f"{name} = {value!r}: must be a finite number >= 0")
        if odometry_check and not max_target_speed > 0.0:
            raise ParameterError("odometry_check = true needs max_target_speed > 0 (the bound "
                                 f"on the source's motion); got {max_target_speed!r}")
        self.odometry_check = (OdometryCheck(max_target_speed, bearing_noise, track_width)
                               if odometry_check else None)
        self.odometry_faults = 0
        self.odometry_stop_until = -math.inf
        self.step_turn = 0.0
        self.step_travel = 0.0
        self.step_size = 0.0
        self.stop_reason = STOP_NONE
        self.max_target_speed = float(max_target_speed)
        self.target_jump_margin = float(target_jump_margin)
        self.fix_timeout = float(fix_timeout)
        self.wheel_check_time = float(wheel_check_time)
        self.wheel_faults = 0
        self.stuck_since_left = None
        self.stuck_since_right = None
        self.wheel_stop_until = -math.inf
        self.rejected_fixes = 0
        self.rejected_in_row = 0
        self.last_accepted_time = 0.0
        self.timed_out = False
        self.track_width = float(track_width)
        self.v_cruise = float(v_cruise)
        self.v_max = float(v_max)
        self.a_max = float(a_max)
        self.stop_distance = float(stop_distance)
        self.mode = MODES[mode]()
        self.odometry = Odometry(track_width)
        self.has_target = False
        self.target_x = 0.0
        self.target_y = 0.0
        self.last_measurement_id = None
        self.fix_outcome = FIX_NONE
        self.started = False
        self.last_time = 0.0
        self.v_ref_left = 0.0
        self.v_ref_right = 0.0
        self.state = IDLE

    @property
    def curvature(self):
        """Signed curvature of the path being driven [1/m], left positive."""
        return self.mode.curvature

    @property
    def radius(self):
        """Radius of the path being driven [m]: 0 when turning on the spot, 1e6 when straight."""
        mode = self.mode
        return 0.0 if mode.turning else radius_of(mode.curvature)

    @property
    def arc_remaining(self):
        """Centre path length still to drive on the current plan [m]."""
        return self.mode.remaining()

    def update(self, time, step_size, wheel_speed_left, wheel_speed_right,
               measurement_id=0, valid=False, distance=0.0, bearing=0.0):
        """Take the inputs at ``time`` and return the wheel speeds to hold for ``step_size``.

        Parameters
        ----------
        time : float
            Current time [s].
        step_size : float
            Time until the next call [s], > 0.
        wheel_speed_left, wheel_speed_right : float
            Measured wheel speeds [m/s], held since the previous call.
        measurement_id : int
            Fix counter; a change marks a new fix.
        valid : bool
            Whether the fix is usable.
        distance : float
            Distance to the target [m].
        bearing : float
            Bearing of the target [rad], left positive, in [-pi, pi].

        Returns
        -------
        tuple of float
            ``(v_ref_left, v_ref_right)`` [m/s].

        Raises
        ------
        InputError
            If a wheel speed, or a valid fix's distance or bearing, is not finite, or the
            bearing is outside [-pi, pi].
        """
        measurement_id, valid = int(measurement_id), bool(valid)
        new_fix = measurement_id != self.last_measurement_id
        # Check every input before touching any state, so a refused step can be retried.
        if not (math.isfinite(wheel_speed_left) and math.isfinite(wheel_speed_right)):
            for port, value in (("wheel_speed_left", wheel_speed_left),
                                ("wheel_speed_right", wheel_speed_right)):
                if not math.isfinite(value):
                    raise InputError(f"{port} = {value!r}: must be finite")
        if new_fix and valid:
            for port, value in (("distance", distance), ("bearing", bearing)):
                if not math.isfinite(value):
                    raise InputError(f"{port} = {value!r} of fix {measurement_id}: must be finite")
            if abs(bearing) > math.pi:
                raise InputError(f"bearing = {bearing!r} of fix {measurement_id}: "
                                 "must lie in [-pi, pi] rad")
        elapsed = time - self.last_time if self.started else 0.0
        self.started = True
        self.last_time = float(time)
        if self.odometry_check is not None:
            heading = self.odometry.heading
            self.odometry.advance(wheel_speed_left, wheel_speed_right, elapsed)
            self.step_turn = abs(self.odometry.heading - heading)
            self.step_travel = abs(0.5 * (wheel_speed_left + wheel_speed_right) * elapsed)
            self.step_size = float(step_size)
        else:
            self.odometry.advance(wheel_speed_left, wheel_speed_right, elapsed)
        mode = self.mode
        mode.record_progress(wheel_speed_left * elapsed, wheel_speed_right * elapsed)
        self.fix_outcome = FIX_NONE
        if new_fix:
            self._observe(time, measurement_id, valid, distance, bearing)
        self.timed_out = (self.fix_timeout > 0.0 and self.has_target
                          and time - self.last_accepted_time > self.fix_timeout)
        desired_left, desired_right = mode.command(self, step_size)
        if self.timed_out:
            # cap the faster wheel, keeping the ratio (the arc's curvature)
            cap = HOLD_SPEED_FACTOR * self.v_cruise
            fastest = max(abs(desired_left), abs(desired_right))
            if fastest > cap:
                desired_left *= cap / fastest
                desired_right *= cap / fastest
        previous_left, previous_right = self.v_ref_left, self.v_ref_right
        left, right, fraction = limit_wheel_change(previous_left, previous_right,
                                                   desired_left, desired_right,
                                                   self.a_max * step_size)
        mode.after_limit(fraction)
        self.stop_reason = STOP_NONE
        if self.wheel_check_time > 0.0 and self._wheel_stuck(time, wheel_speed_left,
                                                             wheel_speed_right):
            left = right = 0.0
            self.stop_reason = STOP_WHEEL
        elif time < self.odometry_stop_until:
            left = right = 0.0
            self.stop_reason = STOP_ODOMETRY
        # The state output, classified here rather than in a helper (this runs every step).
        if left == 0.0 and right == 0.0 and previous_left == 0.0 and previous_right == 0.0:
            self.state = IDLE
        elif mode.turning:
            self.state = TURNING
        elif abs(left + right) < abs(previous_left + previous_right) - 1e-12:
            self.state = STOPPING
        else:
            self.state = MOVING
        self.v_ref_left, self.v_ref_right = left, right
        return left, right

    def _observe(self, time, measurement_id, valid, distance, bearing):
        self.last_measurement_id = measurement_id
        if not valid:
            self.fix_outcome = FIX_INVALID
        elif distance < 0.0:
            self.fix_outcome = FIX_NEGATIVE
        else:
            target_x, target_y = self.odometry.point_at(distance, bearing)
            if self._implausible(time, target_x, target_y):
                self.fix_outcome = FIX_REJECTED
                self.rejected_fixes += 1
                self.rejected_in_row += 1
                return
            self.fix_outcome = FIX_ACCEPTED
            self.rejected_in_row = 0
            if self.odometry_check is not None:
                self._check_odometry(time, target_x, target_y, distance, bearing)
            self.last_accepted_time = float(time)
            self.has_target = True
            self.target_x, self.target_y = target_x, target_y
            self.mode.on_fix(self, distance, bearing)

    def _check_odometry(self, time, target_x, target_y, distance, bearing):
        """The odometry check (see ``odometry_check``): start the stop when it trips."""
        check = self.odometry_check
        tripped = check.observe(time, target_x, target_y, distance, bearing, self.odometry,
                                self.step_turn, self.step_travel, self.step_size)
        if time < self.odometry_stop_until:
            # standing already: the fixes taken while braking are not counted again
            check.reset_count()
        elif tripped:
            self.odometry_faults += 1
            self.odometry_stop_until = time + ODOMETRY_RETRY

    def _implausible(self, time, target_x, target_y):
        """The gate: does the fix imply a target faster than ``max_target_speed``?"""
        if not (self.max_target_speed > 0.0 and self.has_target
                and self.rejected_in_row < REACQUIRE_AFTER):
            return False
        reach = (self.max_target_speed * (time - self.last_accepted_time)
                 + self.target_jump_margin)
        return math.hypot(target_x - self.target_x, target_y - self.target_y) > reach

    def _wheel_stuck(self, time, wheel_speed_left, wheel_speed_right):
        """The wheel check (see ``wheel_check_time``); True while the robot must stand."""
        if time < self.wheel_stop_until:
            return True
        tripped = False
        for side, measured, reference in (("left", wheel_speed_left, self.v_ref_left),
                                          ("right", wheel_speed_right, self.v_ref_right)):
            name = f"stuck_since_{side}"
            if abs(reference) >= WHEEL_CHECK_SPEED and abs(measured) < WHEEL_STUCK_SPEED:
                since = getattr(self, name)
                if since is None:
                    setattr(self, name, float(time))
                elif time - since >= self.wheel_check_time - 1e-9:
                    tripped = True
            else:
                setattr(self, name, None)
        if tripped:
            self.wheel_faults += 1
            self.wheel_stop_until = time + WHEEL_RETRY
            self.stuck_since_left = self.stuck_since_right = None
        return tripped

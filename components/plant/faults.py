"""Plant faults: a sagging supply, encoders that skip or freeze, a low-friction floor patch, a load.

:class:`PlantFaults` answers, for the time at the start of a communication step, what each
wheel gets: its supply voltage (``supply_sag``: the battery sags to ``magnitude`` volts), the
fraction of its encoder counts that reach the MCU (``encoder_skip``: ``1 - magnitude``;
``encoder_freeze``: none) and the friction under its contact point (``low_friction``: ``mu =
magnitude`` while the contact point lies in the fault's region) and the load torque against its
forward rotation (``load_torque``: ``magnitude`` N m at the wheel, a slope, a carpet edge or a
push felt through the wheel; the sum of the active ones). Values are held over the step
(20 ms: 6 mm of travel at 0.3 m/s, far below a patch's size).
"""

from ..common.faults import FaultSchedule

__all__ = ["PlantFaults"]


class PlantFaults:
    """What the scheduled faults do to each wheel at a time.

    Parameters
    ----------
    schedule : FaultSchedule
        Faults of the RobotPlant kinds.
    """

    def __init__(self, schedule=None):
        self.schedule = schedule if schedule is not None else FaultSchedule()

    def __bool__(self):
        return bool(self.schedule)

    def count_active(self, time):
        """Number of faults active at ``time``."""
        return self.schedule.count_active(time)

    def supply(self, time, wheel, nominal):
        """Supply voltage [V] of ``wheel``'s motor driver at ``time``."""
        supply = nominal
        for fault in self.schedule.active(time, "supply_sag"):
            if fault.hits(wheel) and fault.magnitude < supply:
                supply = fault.magnitude
        return supply

    def encoder_keep(self, time, wheel):
        """Fraction of ``wheel``'s encoder counts that are counted at ``time`` (1: healthy)."""
        keep = 1.0
        for fault in self.schedule.active(time):
            if fault.kind == "encoder_freeze" and fault.hits(wheel):
                return 0.0
            if fault.kind == "encoder_skip" and fault.hits(wheel):
                keep = min(keep, 1.0 - fault.magnitude)
        return keep

    def friction(self, time, wheel, x, y, nominal):
        """Friction coefficient under ``wheel``'s contact point (x, y) [m] at ``time``."""
        mu = nominal
        for fault in self.schedule.active(time, "low_friction"):
            if fault.hits(wheel) and fault.covers(x, y):
                mu = min(mu, fault.magnitude)
        return mu

    def load_torque(self, time, wheel):
        """Load torque against ``wheel``'s forward rotation at ``time`` [N m at the wheel]."""
        return sum(fault.magnitude for fault in self.schedule.active(time, "load_torque")
                   if fault.hits(wheel))

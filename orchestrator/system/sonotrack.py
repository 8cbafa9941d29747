"""The sonotrack system as a run sees it: which instance plays which role, and what follows.

The master, the recorder and the runner know instances, ports and connections, never what an
instance is for. What is particular to this system is written here, once, and consulted by
the run layer:

- which instance of ``fmus/SystemStructure.ssd`` plays which role (the instance names of
  :data:`orchestrator.ssp.SONOTRACK_INSTANCES`);
- where the planner's stop distance comes from (:meth:`SonotrackSystem.stop_distance`);
- the recorded columns the run summary reads (:mod:`orchestrator.run.summary`), and those a
  run records whatever its scenario's ``outputs`` list
  (:attr:`SonotrackSystem.recorded_columns`).

Examples
--------
>>> SONOTRACK.planner
'planner'
>>> SONOTRACK.position_columns
('plant.x', 'plant.y', 'source.x', 'source.y')
>>> SONOTRACK.faults_active("localizer")
'localizer.faults_active'
"""

from dataclasses import dataclass

from components.common.errors import ConfigError

__all__ = ["SONOTRACK", "SonotrackSystem"]


@dataclass(frozen=True)
class SonotrackSystem:
    """Which instance plays which role in the sonotrack system; the columns named after them.

    Parameters
    ----------
    source : str
        The sound source: the master robot the tracker follows (its true position).
    localizer : str
        The acoustic localizer: fixes of the source's distance and bearing.
    planner : str
        The curvature planner: wheel speed references; it stops at its stop distance.
    plant : str
        The tracking robot's body and wheels: its true pose, speed and wheel slips.
    wheel_controllers : tuple of str
        The left and right wheel speed controllers.
    stop_distance_parameter : str
        The planner's parameter holding the distance [m] at which it stops.
    """

    source: str = "source"
    localizer: str = "localizer"
    planner: str = "planner"
    plant: str = "plant"
    wheel_controllers: tuple = ("controller_left", "controller_right")
    stop_distance_parameter: str = "stop_distance"

    @property
    def robot_position(self):
        """The robot's true position columns, ``(x, y)`` [m]."""
        return f"{self.plant}.x", f"{self.plant}.y"

    @property
    def source_position(self):
        """The source's true position columns, ``(x, y)`` [m]."""
        return f"{self.source}.x", f"{self.source}.y"

    @property
    def position_columns(self):
        """Robot then source position: a run without all four has no summary figures."""
        return self.robot_position + self.source_position

    @property
    def body_speed(self):
        """The robot body's signed forward speed [m/s]."""
        return f"{self.plant}.speed"

    @property
    def wheel_slips(self):
        """The left and right wheels' slip ratios."""
        return f"{self.plant}.slip_left", f"{self.plant}.slip_right"

    @property
    def fix_attempts(self):
        """The localizer's count of fix attempts so far."""
        return f"{self.localizer}.fix_attempts"

    @property
    def fix_status(self):
        """The localizer's status of its latest attempt (a ``FixStatus`` code, 0 = valid)."""
        return f"{self.localizer}.fix_status"

    @property
    def rejected_fixes(self):
        """The planner's count of fixes its gate rejected."""
        return f"{self.planner}.rejected_fixes"

    @property
    def wheel_check_stops(self):
        """The planner's count of stops by its wheel check."""
        return f"{self.planner}.wheel_faults"

    @property
    def odometry_check_stops(self):
        """The planner's count of stops by its odometry check."""
        return f"{self.planner}.odometry_faults"

    def faults_active(self, instance):
        """The column saying that a fault of ``instance`` is active (> 0)."""
        return f"{instance}.faults_active"

    @property
    def recorded_columns(self):
        """Columns a run records whatever its scenario lists, if the system has them.

        The summary's figures and the plots read them; the order is that of ``results.csv``.
        """
        return (self.source_position + self.robot_position
                + (f"{self.plant}.heading", self.body_speed) + self.wheel_slips
                + (self.fix_attempts, self.fix_status, self.rejected_fixes,
                   self.faults_active(self.localizer), self.faults_active(self.source),
                   self.faults_active(self.plant)))

    def stop_distance(self, system, parameters):
        """The planner's stop distance [m] in a run.

        The run's value if it sets one (a ``.ssd`` binding or a scenario override), else the
        planner FMU's start value, else 0 (a system without a planner).

        Parameters
        ----------
        system : orchestrator.system.System
            The run's system.
        parameters : dict of str to dict
            The run's parameter values per instance
            (:func:`orchestrator.run.parameters.instance_parameters`).

        Returns
        -------
        float
        """
        name = self.stop_distance_parameter
        planner = parameters.get(self.planner, {})
        if name in planner:
            return float(planner[name])
        try:
            component = system.component(self.planner)
        except ConfigError:
            return 0.0
        for variable in component.model_description.modelVariables:
            if variable.name == name and variable.start is not None:
                return float(variable.start)
        return 0.0


SONOTRACK = SonotrackSystem()

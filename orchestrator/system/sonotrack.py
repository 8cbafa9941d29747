"""The sonotrack system as a run sees it: which instance plays which role, and what follows.

The master, the recorder and the runner know instances, ports and connections, never what an
instance is for. What is particular to this system is written here, once, and consulted by
the run layer:

- which instance of ``fmus/SystemStructure.ssd`` plays which role (the instance names of
  :data:`orchestrator.ssp.SONOTRACK_INSTANCES`);
- where the planner's stop distance comes from (:meth:`SonotrackSystem.stop_distance`);
- the recorded columns the run summary reads (:mod:`orchestrator.run.summary`), those the
  plots draw (:mod:`orchestrator.run.plots`), and those a run records whatever its scenario's
  ``outputs`` list (:attr:`SonotrackSystem.recorded_columns`);
- which wheel controller law a run uses (:meth:`SonotrackSystem.controller_mode`), for the
  titles of its plots.

Examples
--------
>>> SONOTRACK.planner
'planner'
>>> SONOTRACK.position_columns
('plant.x', 'plant.y', 'source.x', 'source.y')
>>> SONOTRACK.faults_active("localizer")
'localizer.faults_active'
>>> SONOTRACK.gain("left", "kp"), SONOTRACK.wheel_speed("right")
('controller_left.kp', 'plant.wheel_speed_right')
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
    controller_mode_parameter : str
        The wheel controllers' parameter naming their control law.
    """

    source: str = "source"
    localizer: str = "localizer"
    planner: str = "planner"
    plant: str = "plant"
    wheel_controllers: tuple = ("controller_left", "controller_right")
    stop_distance_parameter: str = "stop_distance"
    controller_mode_parameter: str = "mode"
    sides: tuple = ("left", "right")

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

    @property
    def odometry_position(self):
        """The robot's dead-reckoned position columns, ``(x, y)`` [m]."""
        return f"{self.plant}.odom_x", f"{self.plant}.odom_y"

    @property
    def robot_heading(self):
        """The robot's true heading [rad]."""
        return f"{self.plant}.heading"

    def wheel_speed(self, side):
        """The wheel speed the encoder measures (counts over a window) [m/s]."""
        return f"{self.plant}.wheel_speed_{side}"

    def rim_speed(self, side):
        """The wheel's true rim speed [m/s]."""
        return f"{self.plant}.rim_speed_{side}"

    def wheel_reference(self, side):
        """The planner's speed reference for that wheel [m/s]."""
        return f"{self.planner}.v_ref_{side}"

    def controller(self, side):
        """The wheel controller instance of ``side`` (``left`` or ``right``)."""
        return self.wheel_controllers[self.sides.index(side)]

    def gain(self, side, name):
        """A scheduled gain (``kp`` or ``kd``) of the controller of ``side``."""
        return f"{self.controller(side)}.{name}"

    @property
    def gain_columns(self):
        """``kp`` and ``kd`` of both controllers (the gains plot reads them)."""
        return tuple(self.gain(side, name) for side in self.sides for name in ("kp", "kd"))

    @property
    def fix_columns(self):
        """The localizer's latest fix: distance [m], bearing [rad], valid."""
        return tuple(f"{self.localizer}.{name}" for name in ("distance", "bearing", "valid"))

    def faults_active(self, instance):
        """The column saying that a fault of ``instance`` is active (> 0)."""
        return f"{instance}.faults_active"

    @property
    def recorded_columns(self):
        """Columns a run records whatever its scenario lists, if the system has them.

        The summary's figures and the plots read them; the order is that of ``results.csv``
        (the gains and true rim speeds last: the plots need them, the summary does not).
        """
        return (self.source_position + self.robot_position
                + (self.robot_heading, self.body_speed) + self.wheel_slips
                + (self.fix_attempts, self.fix_status, self.rejected_fixes,
                   self.faults_active(self.localizer), self.faults_active(self.source),
                   self.faults_active(self.plant))
                + self.gain_columns + tuple(self.rim_speed(side) for side in self.sides))

    def parameter(self, system, parameters, instance, name):
        """A parameter's value in a run: the run's, else the FMU's start value, else None.

        Parameters
        ----------
        system : orchestrator.system.System
            The run's system.
        parameters : dict of str to dict
            The run's parameter values per instance
            (:func:`orchestrator.run.parameters.instance_parameters`).
        instance, name : str
            The instance and its parameter.
        """
        values = parameters.get(instance, {})
        if name in values:
            return values[name]
        try:
            component = system.component(instance)
        except ConfigError:
            return None
        for variable in component.model_description.modelVariables:
            if variable.name == name:
                return variable.start
        return None

    def controller_mode(self, system, parameters):
        """The wheel controllers' law in a run (``fgs_pd``, ``pid``, ``pd``), as one text.

        ``"left-law / right-law"`` when the two differ; ``""`` without controllers.
        """
        modes = [self.parameter(system, parameters, c, self.controller_mode_parameter)
                 for c in self.wheel_controllers]
        modes = [str(m) for m in dict.fromkeys(modes) if m is not None]
        return " / ".join(modes)

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
        value = self.parameter(system, parameters, self.planner, self.stop_distance_parameter)
        return 0.0 if value is None else float(value)


SONOTRACK = SonotrackSystem()

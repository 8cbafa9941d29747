"""The wheel controllers `verify` judges, and what each means on the linear loop.

Three designs (:data:`DESIGNS`): the default form of the FGS-PD (what WheelController runs
unless told otherwise), the paper's form, and the paper's CPID. Each is a set of
:class:`components.control.WheelSpeedController` parameters on top of the controller
settings a verification runs with.

:func:`loop_gains` maps one frozen (kp, kd) of a form onto the gains of
:class:`.loop_model.WheelLoopModel`, whose controller is the paper form's law
``g (kp e + kd (e_range/de_range) de + ki integral(e))``: the default form's
``g s (kp e + kd T_d de) + g k_i integral(e)`` is the same law with kp -> s kp,
kd -> s kd T_d / (e_range/de_range) and ki -> k_i. :func:`loop_model` builds the model with
the form's feedforward (the default form's inertia term included).
"""

from dataclasses import replace

from components.common.errors import ConfigError
from components.control.controller import DEFAULTS as CONTROLLER_DEFAULTS
from components.control.controller import FORM_PARAMETERS

__all__ = ["DESIGNS", "DESIGN_LABELS", "OFF_NOMINAL_DESIGNS", "UNCOMMISSIONED", "design_settings", "is_default_form", "loop_gains",
           "loop_model", "integral_gain"]

DESIGNS = {
    "default": {"mode": "fgs_pd", "form": "default"},
    "paper": {"mode": "fgs_pd", "form": "paper"},
    "pid": {"mode": "pid"},
}
DESIGN_LABELS = {"default": "FGS-PD, default form", "paper": "FGS-PD, paper form",
                 "pid": "CPID (the paper's PID)",
                 "default_uncommissioned": "FGS-PD, default form, RobotPlant's constants"}
# The off-nominal requirements judge every design commissioned on each wheel
# (orchestrator/verify/commissioning.py), and show the default form also as shipped, told
# RobotPlant's constants whatever the wheel (a finding: what commissioning buys).
OFF_NOMINAL_DESIGNS = {"default": "default", "paper": "paper", "pid": "pid",
                       "default_uncommissioned": "default"}
UNCOMMISSIONED = ("default_uncommissioned",)


def design_settings(settings, design):
    """The controller parameters of ``design`` on top of ``settings``.

    Parameters
    ----------
    settings : dict
        Controller parameters (:data:`components.control.DEFAULTS` with overrides).
    design : str
        A key of :data:`DESIGNS`. The parameters only the other form reads are put back
        to their defaults (the controller refuses them otherwise).

    Returns
    -------
    dict
    """
    if design not in DESIGNS:
        raise ConfigError(f"verify: design {design!r} is not one of {', '.join(DESIGNS)}")
    out = dict(settings, **DESIGNS[design])
    # a form refuses the other form's parameters unless they are at their defaults
    for form, names in FORM_PARAMETERS.items():
        if form != out.get("form", "default"):
            out.update({name: CONTROLLER_DEFAULTS[name] for name in names})
    return out


def is_default_form(settings):
    """Whether the FGS-PD / PD of ``settings`` is the default form (the PID never is)."""
    return settings.get("form", "default") == "default" and settings.get("mode") != "pid"


def integral_gain(settings):
    """The FGS-PD / PD's integral gain on the integral of ``e`` [1/s], in either form."""
    return float(settings["integral_gain"] if settings.get("form", "default") == "default"
                 else settings["trim_ki"])


def loop_gains(settings, kp, kd):
    """``(kp, kd, ki)`` of :class:`.WheelLoopModel` for one frozen FGS-PD / PD gain set.

    Parameters
    ----------
    settings : dict
        Controller parameters (the form decides the mapping; see the module docstring).
    kp, kd : float
        The gains in the form's own units (the paper's boxes).

    Returns
    -------
    tuple of float
    """
    if settings.get("form", "default") == "default":
        scale = float(settings["gain_scale"])
        paper_time = settings["e_range"] / settings["de_range"]
        return (scale * kp, scale * kd * settings["derivative_time"] / paper_time,
                float(settings["integral_gain"]))
    return float(kp), float(kd), float(settings["trim_ki"])


def loop_model(model, settings):
    """``model`` with the feedforward of ``settings``' form (the default form's inertia term
    and speed observer).

    Parameters
    ----------
    model : WheelLoopModel
    settings : dict

    Returns
    -------
    WheelLoopModel
    """
    default = is_default_form(settings)
    inertia = float(settings["acceleration_feedforward"]) if default else 0.0
    observer = float(settings.get("speed_observer", 0.0)) if default else 0.0
    return replace(model, feedforward=bool(settings["feedforward"]),
                   acceleration_feedforward=inertia, speed_observer=observer,
                   observer_time_constant=inertia if observer else 0.0)

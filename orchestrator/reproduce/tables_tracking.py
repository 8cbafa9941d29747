"""Sec. 6.2 (tracking the moving source): every arm from every start, claims that can fail.

The source starts 1 m or 3 m away at 45 deg right (:data:`~.experiments.SEC62_STARTS`).
Every arm (curvature with CFGS-PD, rotate-then-go with CFGS-PD, curvature with CPID) is judged
on bounds that belong to neither the planner nor the paper (:mod:`.following`): it keeps up
(median gap over the source's second half of travel below its starting gap), keeps to the
source's lane (RMS distance from the source's path below one body length), does not collide;
on the S-curve the paper's "runs inside" is judged too. Figs. 7-8's "curvature tracks more
accurately than rotate-then-go" compares each mode against its own plan, and against the
source's lane, which is neither mode's plan.
"""

import math

from orchestrator.report.document import Verdict

from .claims import Claim, mechanism_text, paired_at_arrival
from .experiments import CONTROLLERS, SEC62_ARMS, SEC62_STARTS, sec62_cell
from .following import BODY_LENGTH
from .report import VERDICT_TONES, Table

__all__ = ["tracking_tables", "condition_summary"]

_MODES = {"curvature": "curvature", "rotate_then_go": "rotate then go"}
# Resolution floors of the "no effect" margin: 5 mm of path distance, one 20 ms sample.
_RESOLUTION = {"rmse_own_plan_m": 5e-3, "lane_rms_m": 5e-3, "slip_time_s": 0.02}


def _arm(mode, arm):
    return f"{_MODES[mode]}, {CONTROLLERS[arm]}"


def _bound(analysis, source, text, condition, cell, key, bound, claimed, why, label):
    # a failed run is the worst outcome on the claim's side (-inf for "above", +inf for
    # "below"), as a lost run is in a paired claim: left out, a run that drove through the
    # source and then out of the room would leave "the robots do not collide" supported
    worst = -math.inf if claimed == "above" else math.inf
    samples = [worst if figures is None else figures.get(key)
               for figures in analysis.figures(cell)]
    return Claim(source, text, condition, f"{key} per run", samples,
                 claimed, "m", threshold=bound, margin=0.0, comparator=why,
                 failures=sum(1 for f in analysis.figures(cell) if f is None), cells=(cell,),
                 reason=mechanism_text(analysis, {label: cell}, "tracking"))


def _paired(analysis, source, text, condition, key, better, comparator, labels, tally=True):
    samples, losses = paired_at_arrival(analysis, better, comparator, key)
    values = sorted(v for v in analysis.values(comparator, key) if v is not None)
    scale = abs(values[len(values) // 2]) if values else 0.0
    return Claim(source, text, condition, f"paired difference {key}({labels[0]}) - "
                 f"{key}({labels[1]})", samples, "below", "m" if key.endswith("_m") else "s",
                 paper_text="(figures / text only)",
                 margin=max(0.1 * scale, _RESOLUTION[key]), comparator=labels[1],
                 failures=losses, cells=(better, comparator), tally=tally,
                 reason=mechanism_text(analysis, {labels[0]: better, labels[1]: comparator},
                                       "tracking"))


def tracking_tables(analysis):
    """Sec. 6.2: one table over every path, start and arm; the tracking claims."""
    t = Table("sec6_2", "Sec. 6.2: tracking the moving source (45 deg right, 1 m and 3 m)",
              [("path", "source path", ""), ("start", "start [m]", ".0f"),
               ("arm", "planner, controller", ""),
               ("late_gap", "median gap, 2nd half [m]", ".3f"),
               ("lane", "RMS from source path, 2nd half [m]", ".3f"),
               ("own_plan", "RMS from own plan [m]", ".3f"),
               ("min_gap", "smallest gap [m]", ".3f"),
               ("inward", "inward offset at apexes [m]", ".3f"),
               ("slip", "slip time [s]", ".2f")])
    claims = []
    for path in ("straight", "s_curve"):
        source = "Sec. 6.2.1" if path == "straight" else "Sec. 6.2.2"
        for start, distance in SEC62_STARTS.items():
            for mode, arm in SEC62_ARMS:
                cell = sec62_cell(path, start, mode, arm)
                if not analysis.has(cell):
                    continue
                label = _arm(mode, arm)
                t.rows.append({"path": path, "start": distance, "arm": label,
                               "late_gap": analysis.estimate(cell, "late_gap_m"),
                               "lane": analysis.estimate(cell, "lane_rms_m"),
                               "own_plan": analysis.estimate(cell, "rmse_own_plan_m"),
                               "min_gap": analysis.estimate(cell, "min_gap_m"),
                               "inward": (analysis.estimate(cell, "inward_offset_m")
                                          if path == "s_curve" else None),
                               "slip": analysis.estimate(cell, "slip_time_s")})
                condition = f"{path}, start {distance:g} m, {label}"
                claims += [
                    _bound(analysis, source, "the robot keeps up with the source (median gap "
                           "over the source's second half of travel below the starting gap)",
                           condition, cell, "late_gap_m", distance, "below",
                           "the starting gap", label),
                    _bound(analysis, source, "the robot follows the source's path (RMS "
                           "distance from it over the second half below one body length)",
                           condition, cell, "lane_rms_m", BODY_LENGTH, "below",
                           "one body length (0.35 m)", label),
                    _bound(analysis, source, "the robots do not collide (smallest gap above "
                           "one body length)", condition, cell, "min_gap_m", BODY_LENGTH,
                           "above", "one body length (0.35 m)", label)]
                if path == "s_curve":
                    claims.append(_bound(analysis, source, "the robot runs inside the source's "
                                         "path (inward offset at the apexes above 0)",
                                         condition, cell, "inward_offset_m", 0.0, "above",
                                         "0 (on the source's path)", label))
            curvature = sec62_cell(path, start, "curvature", "fgs_pd")
            rotate = sec62_cell(path, start, "rotate_then_go", "fgs_pd")
            pid = sec62_cell(path, start, "curvature", "cpid")
            condition = f"{path}, start {distance:g} m"
            if analysis.has(curvature) and analysis.has(rotate):
                # the paper's claim on the source's lane (neither mode's plan); the
                # own-plan metric (how faithfully each mode drives its plan) listed apart
                for key, what, tally in (("lane_rms_m", "the source's lane", True),
                                         ("rmse_own_plan_m", "its own plan", False)):
                    claims.append(_paired(
                        analysis, "Figs. 7-8" if tally else "design", "curvature motion "
                        f"control tracks more accurately than rotate then go (RMS distance "
                        f"from {what})", f"{condition}, {CONTROLLERS['fgs_pd']}", key,
                        curvature, rotate, ("curvature", "rotate then go"), tally))
            if analysis.has(curvature) and analysis.has(pid):
                claims.append(_paired(
                    analysis, "Sec. 6.2 / 7", "CFGS-PD makes the wheels slip less than CPID "
                    "(slip time)", f"{condition}, curvature", "slip_time_s", curvature, pid,
                    (CONTROLLERS["fgs_pd"], "CPID")))
    t.notes += ["Bounds independent of the planner: the starting gap (keeps up), one body "
                f"length {BODY_LENGTH} m (lane, collision), 0 (inside); definitions in "
                "orchestrator/reproduce/following.py and the Definitions section.",
                "'RMS from own plan': each mode against the plan in force (curvature: the arc "
                "planned at its latest fix; rotate then go: the leg planned when it started; "
                "zero for a robot that drives its plan exactly): favours neither mode."]
    return {"sec6_2": t}, claims


def condition_summary(claims):
    """Claims judged under several conditions: which verdict under which condition.

    Returns
    -------
    Table
        One row per claim text with more than one condition, and whether the verdict depends
        on the condition.
    """
    groups = {}
    for claim in claims:
        if claim.tally:
            groups.setdefault((claim.source, claim.claim), []).append(claim)
    table = Table("conditions", "Claims under the stated conditions",
                  [("claim", "claim", ""), ("verdicts", "verdict by condition", ""),
                   ("depends", "depends on the condition", "")])
    for (source, text), group in groups.items():
        if len(group) < 2:
            continue
        # each verdict shown in its tone; the JSON keeps the text (Table.to_dict)
        verdicts = [part for number, c in enumerate(group)
                    for part in (("; " if number else "") + f"{c.condition}: ",
                                 Verdict(c.verdict, VERDICT_TONES[c.verdict]))]
        depends = len({c.verdict for c in group}) > 1
        table.rows.append({"claim": f"{source}: {text}", "verdicts": verdicts,
                           "depends": "yes" if depends else "no"})
    table.notes.append("'yes': the claim holds under some stated conditions and not under "
                       "others; the verdict is then about the condition, not the controller "
                       "alone.")
    return table

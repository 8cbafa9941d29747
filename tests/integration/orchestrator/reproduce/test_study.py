"""A reduced reproduction study on freshly built FMUs, through the same code as the full one.

Two runs per cell, stop times x0.25 and two speeds: the numbers mean little, but every cell,
table, claim, figure and report file is produced by the code path of the full study.
"""

import copy
import json
import re

import pytest

from orchestrator.report.html import embedded_image_sources
from orchestrator.reproduce import reproduce
from tests.support.html_render import ChromiumUnavailable, inspect_report

pytestmark = pytest.mark.integration

RTG = "rotate then go (without curvature)"

PRINTED, DEFAULT = "CFGS-PD as printed", "CFGS-PD default form"
ARMS = ["CPID", PRINTED, DEFAULT, "fixed PD at the median schedule point"]
FIGURES = {
    "fig07_straight_curvature.png": ["source path", "curvature", RTG],
    "fig08_scurve_curvature.png": ["source path", "curvature", RTG],
    "fig13_static_tracking.png": ["ideal", "CPID", PRINTED, f"{PRINTED} - CPID"],
    "fig14_static_left_wheel.png": ["CPID", PRINTED, "slip"],
    "fig14_static_left_wheel_mu005.png": ["CPID", PRINTED, "slip"],
    "fig15_dynamic_tracking.png": ["ideal", "CPID", PRINTED, f"{PRINTED} - CPID"],
    "fig16_dynamic_left_wheel.png": ["CPID", PRINTED, "slip"],
    "fig16_dynamic_left_wheel_mu005.png": ["CPID", PRINTED, "slip"],
    "fig17_static_dynamic_comparison.png": ARMS + ["CPID, ki per sample"],
    "fig23_straight_tracking.png": ["source", "robot", "gap"],
    "fig24_straight_left_wheel.png": ["CPID", DEFAULT, "slip"],
    "fig25_straight_estimates.png": ["true", "heard"],
    "fig26_straight_distance_angle.png": ["true", "heard"],
    "fig27_scurve_tracking.png": ["source", "robot", "gap"],
    "fig28_scurve_left_wheel.png": ["CPID", DEFAULT, "slip"],
    "fig29_scurve_estimates.png": ["true", "heard"],
    "fig30_scurve_distance_angle.png": ["true", "heard"],
    "table1_3_speed_trends.png": [RTG, "curvature"],
    "fig25_straight_estimates_room.png": ["true", "heard"],
    "fig29_scurve_estimates_room.png": ["true", "heard"],
}


def _strings(value):
    if isinstance(value, dict):
        for k, v in value.items():
            yield str(k)
            yield from _strings(v)
    elif isinstance(value, list):
        for v in value:
            yield from _strings(v)
    elif isinstance(value, str):
        yield value


@pytest.fixture(scope="module")
def study(fmu_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("reproduce")
    report = reproduce(out, fmu_dir=fmu_dir, workers=2, progress=False, runs=2,
                       stop_time_scale=0.25, speeds=(0.4, 0.5))
    return out, report


def test_every_figure_is_written_with_its_series(study):
    out, report = study
    written = {f.path.split("/")[-1]: f for f in report.figures}
    assert set(written) == set(FIGURES)
    for name, series in FIGURES.items():
        assert (out / "figures" / name).stat().st_size > 10_000, name
        assert written[name].series == series, name
        assert written[name].path == f"figures/{name}"


def test_reports_hold_tables_verdicts_ratios_and_no_absolute_path(study):
    out, report = study
    data = json.loads((out / "reproduction.json").read_text())
    assert set(data["tables"]) == {"conditions", "table1", "table2", "table3", "table6",
                                   "table7", "table8", "table9", "sec6_2"}
    assert {c["verdict"] for c in data["claims"]} <= {
        "supported", "weaker than claimed", "no effect", "contradicted", "inconclusive"}
    assert all(c["requirement"].startswith(("below", "above")) for c in data["claims"])
    # each claim names its comparator and a reason measured in its cells
    assert all(c["comparator"] and c["reason"] for c in data["claims"])
    # the tally counts the paper's claims only; design comparisons are listed apart
    assert sum(data["verdicts"].values()) == sum(1 for c in data["claims"] if c["tally"])
    assert any(not c["tally"] for c in data["claims"])
    # every printed number of Tables 1-3 (2 speeds), 6-7 and 8-9 (nominal friction; CPID with
    # both readings of its ki and CFGS-PD as printed, feedforward on and off) has a ratio row
    per_table = {}
    for row in data["paper_ratios"]:
        per_table[row["table"]] = per_table.get(row["table"], 0) + 1
    assert per_table == {"Table 1": 6, "Table 2": 8, "Table 3": 4, "Table 6": 8,
                         "Table 7": 13, "Table 8": 36, "Table 9": 12}
    # Table 6 from the simulated wheels: every row has a simulated mean beside the paper's
    assert all(row["ratio"] is not None for row in data["paper_ratios"]
               if row["table"] == "Table 6")
    # 70 free-field cells (Tables 1-3: 4, 6-7: 2, 8-9: 52, Sec. 6.2: 12), and Tables 1-3 and
    # Sec. 6.2 in the room (16)
    assert data["settings"]["runs_per_cell"] == 2 and data["settings"]["cells"] == 86
    assert data["settings"]["conditions"] == ["free_field", "room"]
    kp, kd = data["settings"]["fixed_pd_gains"]
    assert 3.0 <= kp <= 4.0 and 0.3 <= kd <= 2.0     # inside the schedule's boxes
    text = (out / "reproduction.md").read_text() + (out / "reproduction.json").read_text()
    assert str(out) not in text and "/tmp" not in text
    assert not [s for s in _strings(data) if s.startswith("/")]
    markdown = (out / "reproduction.md").read_text()
    assert "](figures/fig07_straight_curvature.png)" in markdown
    assert markdown.index("## Configuration and assumptions") < markdown.index("## Claims")
    assert "feedforward" in markdown.split("## Claims")[0]


def test_html_report_shows_every_figure(study):
    out, report = study
    page = out / "reproduction.html"
    sources = embedded_image_sources(page.read_text())
    assert len(sources) == len(FIGURES)
    assert all(s.startswith("data:image/png;base64,") for s in sources)
    assert not re.search(r'(src|href)="(/|https?:)', page.read_text())
    assert "`" not in page.read_text()   # no raw markup for readers
    try:
        seen = inspect_report(page, screenshot=out / "reproduction.png")
    except ChromiumUnavailable as exc:
        pytest.skip(f"images are embedded data (checked); no browser render: {exc}")
    assert seen["images"] == [len(FIGURES), len(FIGURES)]
    # the answer first: verdict counts and headline claims above everything else
    assert seen["summary_top"] is not None and seen["summary_top"] < 300
    for verdict, count in report.verdict_counts().items():
        assert f"{count} {verdict}" in seen["summary_text"]
    assert seen["contents"] and seen["broken_anchors"] == []
    assert seen["verdict_cells"] >= len(report.claims) and seen["unclassed_verdicts"] == []


def _assert_room_heard(rows):
    """The room's runs heard the room: their fixes err more than free field's in every cell.

    Measured bearing RMSE, room / free field: 4.3-70 in the full study (least for Sec. 6.2
    from 3 m, where the microphones' own offsets and skew already give 0.14 deg in free
    field); in the reduced one (2 short runs a cell) down to 1.4 in a cell.
    """
    ratios = []
    for row in rows:
        free, room = (row["fix_bearing_rmse_deg"][c]["mean"] for c in ("free field", "room"))
        assert room > free, row["cell"]
        ratios.append(room / free)
    assert ratios and sorted(ratios)[len(ratios) // 2] > 3.0, ratios


def test_the_room_check_fails_when_the_room_runs_heard_free_field(study):
    # the silent failure it guards against: a room condition whose runs ran in free field
    # (the same fixes in both columns), or one cell whose room runs did
    out, _ = study
    rows = json.loads((out / "reproduction.json").read_text())["free_field_and_room"][
        "fix_accuracy"]
    _assert_room_heard(rows)
    free_only = copy.deepcopy(rows)
    for row in free_only:
        row["fix_bearing_rmse_deg"]["room"] = dict(row["fix_bearing_rmse_deg"]["free field"])
    with pytest.raises(AssertionError):
        _assert_room_heard(free_only)
    one_cell = copy.deepcopy(rows)
    one_cell[-1]["fix_bearing_rmse_deg"]["room"] = dict(
        one_cell[-1]["fix_bearing_rmse_deg"]["free field"])
    with pytest.raises(AssertionError):
        _assert_room_heard(one_cell)
    with pytest.raises(AssertionError):
        _assert_room_heard([])


def test_every_fix_dependent_claim_is_judged_in_both_conditions_side_by_side(study):
    out, report = study
    data = json.loads((out / "reproduction.json").read_text())["free_field_and_room"]
    # the free-field claims judged on the cells of Tables 1-3 and Sec. 6.2 (not Tables 8-9),
    # the design comparisons among them too, each with a room twin
    fix_dependent = [c for c in report.claims
                     if all(cell.startswith(("t13_", "sec62_")) for cell in c.cells)]
    # Tables 1-2: four slopes; Table 3: one per speed (2); Sec. 6.2 per start (2): three
    # bounds per arm (3) and path (2), the S-curve's inside claim per arm, Figs. 7-8's two
    # metrics (the source's lane, tallied; each mode's own plan, a design comparison) and the
    # slip claim per path
    assert len(data["claims"]) == len(fix_dependent) == 4 + 2 + 2 * (3 * 3 * 2 + 3 + 2 * 3)
    assert all(p["free_field"] and p["room"] for p in data["claims"])
    assert data["room"]["parameters"]["localizer.room"] is True
    assert data["room"]["parameters"]["localizer.rt60"] == 0.4
    assert data["failed_runs"] == {}
    _assert_room_heard(data["fix_accuracy"])
    differing = [p for p in data["claims"] if p["differs"]]
    assert all(p["free_field"]["verdict"] != p["room"]["verdict"] for p in differing)
    assert all(p["why"].startswith("Measured: effect") for p in differing)
    markdown = (out / "reproduction.md").read_text()
    section = markdown.split("## Free field and room")[1].split("\n## ")[0]
    assert "| free field | room |" in section
    lines = section.splitlines()
    for pair in data["claims"]:   # one row per claim: the free-field verdict, then the room's
        verdicts = f"| **{pair['free_field']['verdict']}** | **{pair['room']['verdict']}** |"
        assert any(pair["claim"].replace("|", "\\|") in line and verdicts in line
                   for line in lines), pair["claim"]
    assert f"Claims whose verdict differs between free field and room ({len(differing)})" \
        in section
    assert "scenarios/room.toml" in section


def test_a_second_call_reuses_every_finished_run(study, fmu_dir):
    # last: it rewrites the report folder with Tables 1-3 alone
    out, _ = study
    again = reproduce(out, fmu_dir=fmu_dir, workers=1, progress=False, runs=2,
                      stop_time_scale=0.25, speeds=(0.4, 0.5), tables=("table1",))
    # Tables 1-3's 4 cells x 2 runs, in free field and in the room
    assert again.settings["runs_computed"] == 0 and again.settings["runs_reused"] == 16

"""The command line's own behaviour: help, hints and one-line errors (nothing is run here)."""

import pytest

from orchestrator.cli import main

COMMANDS = ("build", "validate", "run", "sweep", "info", "compare", "verify", "reproduce")


def _call(capsys, *argv):
    try:
        status = main(list(argv))
    except SystemExit as exit_:   # argparse's --help and usage errors
        status = exit_.code
    out, err = capsys.readouterr()
    return status, out, err.strip()


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_has_a_description_and_an_example(capsys, command):
    status, out, _ = _call(capsys, command, "--help")
    assert status == 0
    usage, _, rest = out.partition("\n\n")
    description = rest.split("\n\n")[0]
    assert len(description.split()) >= 8, f"{command}: no description under the usage"
    examples = out.split("examples:\n", 1)[1]
    assert f"sonotrack {command}" in examples


def test_an_unknown_option_points_to_the_help_of_its_command(capsys):
    status, _, err = _call(capsys, "run", "--bogus")
    assert status == 2
    assert err == ("sonotrack run: error: unrecognized arguments: --bogus (see sonotrack run "
                   "--help)")


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_a_set_with_a_space_gets_the_spelling_that_works(capsys, command):
    status, _, err = _call(capsys, command, "--set", "planner.v_cruise", "0.2,0.3")
    assert status == 2
    assert err == (f"sonotrack {command}: error: --set 'planner.v_cruise': no '='; write it "
                   "as one word: --set planner.v_cruise=0.2,0.3")


def test_errors_carry_the_command_prefix_once(capsys, tmp_path):
    status, _, err = _call(capsys, "validate", "--dir", str(tmp_path))
    assert status == 2
    assert err == (f"sonotrack validate: error: no FMU given and none in {tmp_path}; run "
                   "`sonotrack build` first")


@pytest.mark.parametrize("argv, fragment", [
    (["run", "s_curv"], "scenario 's_curv' is neither a file nor a shipped scenario (did you "
                        "mean 's_curve'?)"),
    (["run", "--stop-time", "-3"], "--stop-time '-3': expected a number of seconds"),
    (["run", "--stop-time", "0.005"], "with --stop-time: field 'stop_time': 0.005 is not an "
                                      "integer multiple of base_step 0.01"),
    (["run", "--set", "planner.v_cruise=0.2,0.3"], "a run takes one value per parameter"),
    (["run", "--set", "plannr.v_cruise=0.2"], "no instance 'plannr'"),
    (["sweep", "--stop-time", "abc"], "--stop-time 'abc': expected a number of seconds"),
    (["compare", "runs/nothing_here"], "compare needs two or more run folders, got 1"),
], ids=["unknown-scenario", "negative-stop", "stop-off-grid", "run-list", "bad-instance",
        "sweep-stop", "compare-one"])
def test_bad_command_lines_are_one_line_naming_what_is_wrong(capsys, argv, fragment):
    status, out, err = _call(capsys, *argv)
    assert status == 2 and out == ""
    assert err.startswith(f"sonotrack {argv[0]}: error: ") and err.count("\n") == 0
    assert fragment in err


def test_info_on_a_file_that_is_not_an_fmu(capsys, tmp_path):
    fake = tmp_path / "fake.fmu"
    fake.write_text("not a zip", encoding="utf-8")
    status, _, err = _call(capsys, "info", str(fake))
    assert status == 2 and err.count("\n") == 0
    assert err.startswith(f"sonotrack info: error: {fake}: not an FMU with a readable "
                          "modelDescription.xml")
    status, _, err = _call(capsys, "info", str(tmp_path / "NoSuchModel"))
    assert status == 2 and "NoSuchModel: no such FMU file (nor NoSuchModel.fmu in fmus" in err

"""sonotrack's FMI binary in a C host (fmi_host.c, compiled here with gcc).

The host runs with no LD_PRELOAD and no PYTHONPATH: the binary loads the build's libpython and
starts the build's Python itself, gives fmpy's outputs, and the process exits 0 with or without
dlclose. The same runs under AddressSanitizer, UBSan and LeakSanitizer (a test-only build of the
library and of the host) must report nothing and print the same numbers. How the library finds
Python, and what it says when it cannot, is test_finding_python.py. docs/fmi_binary.md states the
contract.
"""

import shutil
import sys

import pytest

from tests.support.fmi_binary import (NAMES, SANITIZER_FINDINGS, check_host_run, host_env, plan,
                                 run_host)

pytestmark = pytest.mark.integration


@pytest.mark.parametrize("name", NAMES, ids=NAMES)
def test_c_host_without_preload_gives_fmpys_outputs_and_exits_cleanly(c_host, extracted, name):
    plan_text, _ = plan(extracted, [name])
    check_host_run(run_host(c_host, plan_text), [name], extracted)


@pytest.mark.parametrize("flags", [(), ("--keep-loaded",)], ids=["dlclose", "no_dlclose"])
def test_c_host_runs_all_five_fmus_in_one_process(c_host, extracted, flags):
    plan_text, _ = plan(extracted, NAMES)
    check_host_run(run_host(c_host, plan_text, *flags), NAMES, extracted)


def test_c_host_runs_the_builds_python_environment(c_host, probe):
    """Without PYTHONPATH, the interpreter the FMU starts is the build's venv (its numpy)."""
    folder, description = probe
    refs = {v.name: v.valueReference for v in description.modelVariables}
    binary = folder / "binaries" / "linux64" / "Probe.so"
    plan_text = (f"1 1\n{binary} {description.guid} {(folder / 'resources').as_uri()} c_probe "
                 f"0.01 0 1 {refs['action']} 0 1 {refs['elapsed']} 1 {refs['count']} 0\n6\n")
    completed = run_host(c_host, plan_text)
    assert completed.returncode == 0, completed.stderr[-2000:]
    assert completed.stdout.split() == ["0", "0", "0", "1"]  # step 0, FMU 0, elapsed, count
    assert f"sys.prefix={sys.prefix}" in completed.stderr, completed.stderr


# ----- the same runs under AddressSanitizer, UBSan and LeakSanitizer ---------------------------

@pytest.mark.parametrize("flags", [(), ("--keep-loaded",)], ids=["dlclose", "no_dlclose"])
def test_all_five_fmus_under_address_and_undefined_behaviour_sanitizers(c_host, extracted,
                                                                       sanitized, tmp_path,
                                                                       flags):
    host, library, suppressions, _ = sanitized
    copies = {}
    for name in NAMES:  # the same FMUs with the sanitized library in place of the shipped one
        folder, description = extracted[name]
        copy = tmp_path / name
        shutil.copytree(folder, copy)
        shutil.copy(library, copy / "binaries" / "linux64" /
                    f"{description.coSimulation.modelIdentifier}.so")
        copies[name] = (copy, description)
    env = host_env()
    env["ASAN_OPTIONS"] = "detect_leaks=1:halt_on_error=1"
    env["LSAN_OPTIONS"] = f"suppressions={suppressions}:print_suppressions=0"
    env["UBSAN_OPTIONS"] = "print_stacktrace=1:halt_on_error=1"
    completed = run_host(host, plan(copies, NAMES)[0], *flags, env=env)
    assert not any(sign in completed.stderr for sign in SANITIZER_FINDINGS), \
        completed.stderr[-6000:]
    check_host_run(completed, NAMES, extracted)  # fmpy's reference runs the shipped library
    # bit for bit what the shipped (-O2, unsanitized) library prints for the same plan
    shipped = run_host(c_host, plan(extracted, NAMES)[0], *flags)
    assert completed.stdout == shipped.stdout

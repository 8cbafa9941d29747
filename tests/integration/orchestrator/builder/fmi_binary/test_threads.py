"""Many threads instantiating, stepping and freeing sonotrack FMUs at once.

Multi-threaded hosts and FMU containers instantiate from worker threads. For 2 and for 8
threads, in each of the three cases of tests/support/fmi_threads.py (different FMUs; one FMU
from one folder; one FMU from as many copies as threads), 50 runs in fresh processes (the
interpreter's start and a build's first load happen once per process, so only a fresh process
repeats them): a C host with no Python (the library starts the interpreter) and fmpy (the
host's interpreter). Every run exits 0 and prints what the single-threaded C host prints for
the same plan, which in turn equals fmpy's outputs (test_c_host.py).
"""

import shutil
import sys

import pytest

from tests.support.fmi_binary import plan, run_host
from tests.support.fmi_threads import (CASES, FMPY_THREADS, GIL_HELD, RUNS, THREAD_STEPS, entries,
                                       failures, fmpy_spec, run_many, unzipped_copies)

pytestmark = pytest.mark.integration

THREADS = (2, 8)


@pytest.fixture(scope="module")
def copies(extracted, tmp_path_factory):
    return unzipped_copies(extracted, tmp_path_factory.mktemp("copies"), max(THREADS))


@pytest.fixture(scope="module")
def single_threaded(c_host, extracted, copies):
    """(case, threads) -> (plan entries, plan text, what the single-threaded C host prints)."""
    out = {}
    for case in CASES:
        for threads in THREADS:
            plan_entries = entries(case, threads, extracted, copies)
            text, _ = plan(None, plan_entries, THREAD_STEPS)
            completed = run_host(c_host, text)
            assert completed.returncode == 0, completed.stderr[-2000:]
            assert len(completed.stdout.splitlines()) == threads * THREAD_STEPS
            out[case, threads] = (plan_entries, text, completed.stdout)
    return out


@pytest.mark.parametrize("threads", THREADS, ids=[f"{n}_threads" for n in THREADS])
@pytest.mark.parametrize("case", CASES)
def test_c_host_threads_instantiate_step_and_free_at_once(c_host, single_threaded, case, threads):
    _, text, reference = single_threaded[case, threads]
    completed = run_many([str(c_host), "--threads"], RUNS, stdin=text)
    bad = failures(completed, reference)
    print(f"C host, {case}, {threads} threads: {len(bad)} of {RUNS} runs failed")
    assert not bad, f"{len(bad)} of {RUNS} runs failed:\n" + "\n".join(bad[:5])


@pytest.mark.parametrize("threads", THREADS, ids=[f"{n}_threads" for n in THREADS])
@pytest.mark.parametrize("case", CASES)
def test_fmpy_threads_instantiate_step_and_free_at_once(single_threaded, tmp_path, case, threads):
    plan_entries, _, reference = single_threaded[case, threads]
    spec = tmp_path / "spec.json"
    spec.write_text(fmpy_spec(plan_entries, THREAD_STEPS))
    completed = run_many([sys.executable, "-c", FMPY_THREADS, str(spec)], RUNS)
    bad = failures(completed, reference)
    print(f"fmpy, {case}, {threads} threads: {len(bad)} of {RUNS} runs failed")
    assert not bad, f"{len(bad)} of {RUNS} runs failed:\n" + "\n".join(bad[:5])


def test_threads_holding_the_gil_and_threads_without_it_never_deadlock(copies):
    """8 copies instantiated at once in a Python host, half of the calls made holding the GIL
    (ctypes.PyDLL): every run ends (no deadlock between the process mutex and the GIL) with 8
    instances made."""
    arguments = [f"{folder / 'binaries' / 'linux64' / 'WheelController.so'}|{description.guid}|"
                 f"{(folder / 'resources').as_uri()}" for folder, description in copies]
    completed = run_many([sys.executable, "-c", GIL_HELD, *arguments], RUNS, timeout=60)
    bad = failures(completed, "8")
    print(f"Python host, 8 copies, half holding the GIL: {len(bad)} of {RUNS} runs failed")
    assert not bad, f"{len(bad)} of {RUNS} runs failed:\n" + "\n".join(bad[:5])


@pytest.mark.parametrize("case", ["one_folder", "copies"])
def test_no_data_race_under_thread_sanitizer(thread_sanitized, single_threaded, copies, tmp_path,
                                             case):
    """The library and the C host built with ThreadSanitizer, 8 threads at once (in one copy, and
    in 8 copies of the library), 3 fresh processes: no race reported, and the numbers of the
    shipped library. (Seen reporting a race when a copy's ready flag is read without acquire
    ordering.)"""
    host, built = thread_sanitized
    plan_entries, _, reference = single_threaded[case, 8]
    ours = []
    for i, (model, folder, description, instance) in enumerate(plan_entries):
        copy = tmp_path / (f"c{i}" if case == "copies" else "one")
        if not copy.exists():
            shutil.copytree(folder, copy)
            binaries = copy / "binaries" / "linux64"
            shutil.copy(built / "sonotrack_fmi2_tsan.so", binaries / "WheelController.so")
            shutil.copy(built / "libsonotrack_fmi2_lock.so.1", binaries)
        ours.append((model, copy, description, instance))
    text, _ = plan(None, ours, THREAD_STEPS)
    completed = run_many([str(host), "--threads"], 3, stdin=text,
                         extra_env={"TSAN_OPTIONS": "halt_on_error=0 report_signal_unsafe=0"})
    races = [run.stderr for run in completed if "WARNING: ThreadSanitizer" in run.stderr]
    assert not races, races[0][-4000:]
    bad = failures(completed, reference)
    assert not bad, "\n".join(bad[:3])

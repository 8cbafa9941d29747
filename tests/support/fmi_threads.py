"""Running sonotrack FMUs from many threads at once, each run in a fresh process.

The three cases of tests/integration/orchestrator/builder/fmi_binary/test_threads.py: different
FMUs (each from its own folder, so each thread calls another copy of the library), one FMU many
times from one folder (one copy of the library, one build's code loaded by several threads at
once), and one FMU from as many unzipped copies as threads (several copies of the library, one
build). Hosts: the C host (tests/support/fmi_host.c, ``--threads``) and fmpy in a Python
process (:data:`FMPY_THREADS`). Every run must print what the single-threaded C host prints.
"""

import json
import shutil
import subprocess
import textwrap
from concurrent.futures import ThreadPoolExecutor

from tests.support.fmi_binary import ABORT_SIGNS, NAMES, host_env, plan

__all__ = ["CASES", "THREAD_STEPS", "RUNS", "SAME_FMU", "FMPY_THREADS", "GIL_HELD", "entries",
           "unzipped_copies", "fmpy_spec", "run_many", "failures"]

CASES = ("different", "one_folder", "copies")
THREAD_STEPS = 20  # enough to overlap the threads' steps; the instantiations are what collide
RUNS = 50
SAME_FMU = "WheelController"


def entries(case, threads, extracted, copies):
    """The plan entries (model, folder, description, instance name) of one case."""
    if case == "different":
        models = [NAMES[i % len(NAMES)] for i in range(threads)]
        return [(m, *extracted[m], f"t{i}_{m}") for i, m in enumerate(models)]
    if case == "one_folder":
        return [(SAME_FMU, *extracted[SAME_FMU], f"t{i}") for i in range(threads)]
    if case == "copies":
        return [(SAME_FMU, *copies[i], f"t{i}") for i in range(threads)]
    raise ValueError(f"unknown case {case!r}; valid: {', '.join(CASES)}")


def unzipped_copies(extracted, folder, count):
    """``count`` copies of the unzipped SAME_FMU, each in a folder of its own."""
    source, description = extracted[SAME_FMU]
    out = []
    for i in range(count):
        copy = folder / f"copy{i}"
        if not copy.exists():
            shutil.copytree(source, copy)
        out.append((copy, description))
    return out


def fmpy_spec(plan_entries, steps):
    """What FMPY_THREADS needs, as JSON: per FMU its folder, GUID, instance name, step, value
    references by group and the inputs of every step (the C host's plan, in another form)."""
    _, layouts = plan(None, plan_entries, steps)
    fmus = []
    for (model, folder, description, instance), (h, drive, groups) in zip(plan_entries, layouts):
        variables = {v.name: v for v in description.modelVariables}
        fmus.append({
            "folder": str(folder), "guid": description.guid, "instance": instance, "h": h,
            "identifier": description.coSimulation.modelIdentifier,
            "vr": [[variables[n].valueReference for n in group] for group in groups],
            "inputs": [[[float(drive(k * h)[n]) for n in group] for group in groups[:3]]
                       for k in range(steps)],
        })
    return json.dumps({"steps": steps, "fmus": fmus})


# One thread per FMU, each with its own FMU2Slave (fmpy loads the binary with ctypes, calls it
# without the GIL); barriers make the instantiations and the frees coincide, as in fmi_host.c.
FMPY_THREADS = textwrap.dedent('''
    import json, sys, threading
    from fmpy.fmi2 import FMU2Slave

    spec = json.load(open(sys.argv[1]))
    fmus, steps = spec["fmus"], spec["steps"]
    start, end = threading.Barrier(len(fmus)), threading.Barrier(len(fmus))
    rows = [[None] * steps for _ in fmus]
    errors = []

    def run(f, fmu):
        try:
            slave = FMU2Slave(guid=fmu["guid"], unzipDirectory=fmu["folder"],
                              modelIdentifier=fmu["identifier"], instanceName=fmu["instance"])
            start.wait()
            slave.instantiate()
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            vr, h = fmu["vr"], fmu["h"]
            for k in range(steps):
                reals, integers, booleans = fmu["inputs"][k]
                if vr[0]: slave.setReal(vr[0], reals)
                if vr[1]: slave.setInteger(vr[1], [int(x) for x in integers])
                if vr[2]: slave.setBoolean(vr[2], [bool(x) for x in booleans])
                slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
                text = ["%.17g" % x for x in (slave.getReal(vr[3]) if vr[3] else [])]
                text += ["%d" % x for x in (slave.getInteger(vr[4]) if vr[4] else [])]
                text += ["%d" % x for x in (slave.getBoolean(vr[5]) if vr[5] else [])]
                rows[f][k] = " ".join([str(k), str(f)] + text)
            end.wait()
            slave.terminate()
            slave.freeInstance()
        except BaseException as exc:
            errors.append(f"{fmu['instance']}: {exc!r}")
            start.abort()
            end.abort()

    threads = [threading.Thread(target=run, args=(f, fmu)) for f, fmu in enumerate(fmus)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    if errors:
        sys.exit("; ".join(errors))
    print("\\n".join(rows[f][k] for k in range(steps) for f in range(len(fmus))))
''')


# Threads of a Python host instantiating at once, half of them through ctypes.PyDLL (the GIL stays
# held during the call, as in a host that calls FMI functions from C code holding it) and half
# through ctypes.CDLL (the GIL released, as fmpy calls). A thread starting its copy of the library
# holds the process mutex and then needs the GIL; a PyDLL thread waiting for that mutex with the
# GIL held would block both forever, unless it lets the GIL go while it waits. Argument: lines
# "binary|guid|resource uri". Prints the number of instances made.
GIL_HELD = textwrap.dedent('''
    import ctypes, sys, threading

    entries = [line.split("|") for line in sys.argv[1:]]
    start = threading.Barrier(len(entries))
    made = []

    def run(i, binary, guid, uri):
        loader = ctypes.PyDLL if i % 2 else ctypes.CDLL
        library = loader(binary)
        instantiate, free = library.fmi2Instantiate, library.fmi2FreeInstance
        instantiate.restype = ctypes.c_void_p
        instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                                ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
        free.argtypes = [ctypes.c_void_p]
        start.wait()
        component = instantiate(f"g{i}".encode(), 1, guid.encode(), uri.encode(), None, 0, 0)
        if component:
            made.append(i)
            free(component)

    threads = [threading.Thread(target=run, args=(i, *entry)) for i, entry in enumerate(entries)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    print(len(made))
''')


def run_many(command, runs, stdin=None, parallel=2, timeout=300, extra_env=None):
    """Run ``command`` ``runs`` times, each in a fresh process, ``parallel`` at a time; a run
    still going after ``timeout`` seconds is killed and counts as exit status -9."""
    env = dict(host_env(), **(extra_env or {}))

    def one(_):
        try:
            return subprocess.run(command, input=stdin, capture_output=True, text=True,
                                  env=env, cwd="/", timeout=timeout)
        except subprocess.TimeoutExpired as expired:
            return subprocess.CompletedProcess(command, -9, "", f"timed out after {timeout} s "
                                               f"(a deadlock?) {expired.stderr or ''}")

    with ThreadPoolExecutor(max_workers=parallel) as pool:
        return list(pool.map(one, range(runs)))


def failures(completed, reference):
    """The runs that did not exit 0, printed an abort sign or printed other numbers."""
    bad = []
    for i, run in enumerate(completed):
        if run.returncode != 0 or any(s in run.stderr for s in ABORT_SIGNS) \
                or run.stdout.strip() != reference.strip():
            reason = f"exit {run.returncode}" if run.returncode else "other output"
            bad.append(f"run {i}: {reason}: {run.stderr.strip()[-300:]}")
    return bad


"""reproduce() called from a plain script, as a user writes one: no ``__main__`` guard."""

import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.integration


def test_a_script_without_a_main_guard_runs_the_study_once(fmu_dir, tmp_path):
    # 100 runs: enough that the runs are read back by a pool of processes (one per 50 runs),
    # which must not run this script again
    script = tmp_path / "study.py"
    script.write_text(textwrap.dedent(f"""
        from orchestrator.reproduce import reproduce
        print("script started", flush=True)
        report = reproduce({str(tmp_path / 'out')!r}, fmu_dir={str(fmu_dir)!r}, workers=2,
                           progress=False, runs=25, stop_time_scale=0.1, speeds=(0.4, 0.5),
                           tables=("table1",), conditions=["free_field"])
        print("runs", report.settings["runs_total"], "computed", report.settings["runs_computed"])
    """))
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.count("script started") == 1, done.stdout
    assert "runs 100 computed 100" in done.stdout

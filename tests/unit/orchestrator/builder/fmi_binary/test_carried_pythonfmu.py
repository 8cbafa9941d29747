"""The pythonfmu an FMU carries: run-time modules only, under the build's private name.

On a small made-up pythonfmu (so the expected closure is known independently) and on the one
installed here (pythonfmu 0.7.0, whose run-time modules are listed by hand).
"""

import pytest

from components.common.errors import BuildError
from orchestrator.builder.fmi_binary.carried_pythonfmu import (carry, installed_runtime,
                                                               runtime_modules)

INIT = (b"from ._version import __version__\n"
        b"from .builder import FmuBuilder\n"
        b"from .core import Slave\n")
TOY = {"__init__.py": INIT, "_version.py": b"__version__ = '9'\n",
       "builder.py": b"from .core import Slave\nimport zipfile\n",
       "core.py": b"from .helpers import helper\nfrom . import enums\n",
       "helpers.py": b"helper = 1\n", "enums.py": b"A = 1\n", "deploy.py": b"import os\n",
       "__main__.py": b"from .builder import FmuBuilder\n"}


def test_the_closure_of_the_runtime_init_is_what_ships():
    modules = runtime_modules(TOY)
    assert set(modules) == {"__init__.py", "_version.py", "core.py", "helpers.py", "enums.py"}
    assert modules["__init__.py"] == (b"from ._version import __version__\n"
                                      b"from .core import Slave\n")
    assert modules["core.py"] == TOY["core.py"]


@pytest.mark.parametrize("source, words", [
    (b"from .builder import FmuBuilder\n", "needs the build-time module builder"),
    (b"from .missing import x\n", "imports .missing, which the package lacks"),
    (b"import pythonfmu.enums\n", "imports pythonfmu by its public name"),
    (b"from pythonfmu import enums\n", "imports pythonfmu by its public name"),
], ids=["build_time", "missing", "public_import", "public_from"])
def test_a_runtime_module_that_cannot_be_carried_is_refused(source, words):
    with pytest.raises(BuildError, match=words):
        runtime_modules(dict(TOY, **{"core.py": source}))


def test_the_installed_pythonfmu_carries_its_seven_runtime_modules():
    assert set(installed_runtime()) == {"__init__.py", "_version.py", "enums.py", "fmi2slave.py",
                                        "variables.py", "default_experiment.py", "logmsg.py"}
    assert b"builder" not in installed_runtime()["__init__.py"]


def test_carry_moves_pythonfmu_under_the_package_and_rewrites_the_imports():
    files = {f"resources/pythonfmu/{name}": data for name, data in TOY.items()}
    files["resources/pkg/common/slave.py"] = (b'"""from pythonfmu\'s docs"""\n'
                                              b"from pythonfmu import Fmi2Slave\n"
                                              b"    from pythonfmu.enums import A\n")
    files["resources/Model.py"] = b"from pkg.common.slave import Fmi2Slave\n"
    files["resources/other.txt"] = b"from pythonfmu import x\n"  # not Python: left alone
    carry(files, "pkg", "Model")
    assert sorted(files) == sorted(
        ["resources/pkg/common/slave.py", "resources/Model.py", "resources/other.txt"] +
        [f"resources/pkg/_pythonfmu/{n}" for n in
         ("__init__.py", "_version.py", "core.py", "helpers.py", "enums.py")])
    assert files["resources/pkg/common/slave.py"] == (b'"""from pythonfmu\'s docs"""\n'
                                                      b"from pkg._pythonfmu import Fmi2Slave\n"
                                                      b"    from pkg._pythonfmu.enums import A\n")
    assert files["resources/other.txt"] == b"from pythonfmu import x\n"


def test_carry_refuses_an_import_it_cannot_make_private():
    files = {f"resources/pythonfmu/{name}": data for name, data in TOY.items()}
    files["resources/pkg/fmu.py"] = b"import pythonfmu\n"
    with pytest.raises(BuildError, match="resources/pkg/fmu.py: imports pythonfmu in a form"):
        carry(files, "pkg", "Model")

"""The README as a user reads it: its commands parse, its links resolve, its examples work,
and nothing in the repository cites a file outside it."""

import re
import shlex
import subprocess
from pathlib import Path

import pytest

from orchestrator.builder.fmus import REPO_ROOT
from orchestrator.cli import _parser

README = REPO_ROOT / "README.md"
TEXT = README.read_text(encoding="utf-8")
DOCS = sorted((REPO_ROOT / "docs").glob("*.md"))


def _blocks(language):
    return re.findall(rf"```{language}\n(.*?)```", TEXT, flags=re.S)


def _commands():
    """Every ``sonotrack ...`` line of the README's shell blocks and of its commands table."""
    lines = [line.split("#")[0].strip() for block in _blocks("sh") for line in
             block.splitlines()]
    lines += re.findall(r"^\| `(sonotrack [^`]*)` \|", TEXT, flags=re.M)
    return [line for line in lines if line.startswith("sonotrack ")]


def test_the_readme_is_a_short_guide_with_its_fixed_sections():
    assert len(TEXT.splitlines()) <= 200
    headings = re.findall(r"^## (.+)$", TEXT, flags=re.M)
    for needed in ("Requirements and set-up", "Commands", "Reports", "How to cite",
                   "Troubleshooting"):
        assert needed in headings
    assert re.search(r"!\[[^\]]+\]\(docs/images/[^)]+\.png\)", TEXT), "no picture"


def test_the_set_up_commands_are_what_ci_runs():
    set_up = [line.split("#")[0].strip() for line in _blocks("sh")[0].splitlines()]
    ci = [line.strip() for line in (REPO_ROOT / ".ci" / "run").read_text().splitlines()
          if line.startswith("make")]
    assert set_up == ci == ["make demo", "make test"]
    for target in ("demo", "test"):   # and make knows them
        done = subprocess.run(["make", "-n", target], cwd=REPO_ROOT, capture_output=True,
                              text=True, timeout=60)
        assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("line", _commands())
def test_every_command_in_the_readme_parses(line):
    words = shlex.split(line)[1:]
    words = [w.replace("K=V1,V2", "planner.v_cruise=0.2,0.3") for w in words
             if w not in ("...", "FMU", "RUN_DIR...", "[NAME", "...]", "[FMU", "[SCENARIO]")]
    if words[0] == "info" and len(words) == 1:
        words.append("fmus/RobotPlant.fmu")
    if words[0] == "compare" and len(words) == 1:
        words += ["runs/a", "runs/b"]
    parser = _parser(words[0])
    args, unknown = parser.parse_known_args(words)
    assert unknown == [] and args.command == words[0]


def _links(path):
    text = path.read_text(encoding="utf-8")
    return [target for target in re.findall(r"\]\(([^)\s]+)\)", text)
            if not re.match(r"[a-z]+:", target)]


def _anchors(path):
    """GitHub's heading anchors of a Markdown file."""
    headings = re.findall(r"^#+ (.+)$", path.read_text(encoding="utf-8"), flags=re.M)
    return {re.sub(r"[^a-z0-9 _-]", "", h.lower()).replace(" ", "-") for h in headings}


@pytest.mark.parametrize("path", [README] + DOCS, ids=lambda p: p.name)
def test_every_link_resolves_to_a_file_and_heading_of_the_repository(path):
    for target in _links(path):
        file, _, anchor = target.partition("#")
        resolved = (path.parent / file).resolve() if file else path
        assert resolved.exists(), f"{path.name}: {target} does not exist"
        assert resolved.is_relative_to(REPO_ROOT), f"{path.name}: {target} leaves the repository"
        if anchor:
            assert anchor in _anchors(resolved), f"{path.name}: no heading #{anchor}"


def test_every_docs_page_is_in_the_index():
    index = (REPO_ROOT / "docs" / "README.md").read_text(encoding="utf-8")
    for page in DOCS:
        if page.name != "README.md":
            assert f"]({page.name})" in index, f"docs/README.md does not list {page.name}"


def test_the_minimal_scenario_of_the_readme_is_valid(tmp_path):
    from orchestrator.scenario import load_scenario

    (scenario_text,) = _blocks("toml")
    path = tmp_path / "my.toml"
    path.write_text(scenario_text, encoding="utf-8")
    scenario = load_scenario(path)
    assert scenario.name == "follow_straight" and scenario.stop_time == 20.0
    assert scenario.parameters == {"source.path": "straight", "planner.v_cruise": 0.3}


# Names of files outside the repository that its text once cited.
_OUTSIDE = re.compile(r"DESIGN\.md|STYLE\.md|\.\./shared|/work/shared|shared/paper")
_TEXT_SUFFIXES = {".py", ".md", ".toml", ".txt", ".c", ".h", ".ssd", ".ssv", ".cfg", ".ini",
                  ".json", ".csv", ".yml", ".yaml", ""}


def test_nothing_in_the_repository_cites_a_file_outside_it():
    listed = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard"],
                            cwd=REPO_ROOT, capture_output=True, text=True, check=True)
    offenders = []
    for name in listed.stdout.splitlines():
        path = REPO_ROOT / name
        if path.suffix not in _TEXT_SUFFIXES or not path.is_file() or \
                name == "tests/unit/test_readme.py":
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        offenders += [f"{name}:{n}" for n, line in enumerate(text.splitlines(), 1)
                      if _OUTSIDE.search(line)]
    assert offenders == []


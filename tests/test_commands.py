"""Every shell command the README and the documentation pages show runs, as written, on
small inputs (so that none can drift from the code).

Each fenced shell block (``sh``, ``bash``, ``shell``, ``console``) of ``README.md`` and of
``docs/**/*.md`` carries a marker, an HTML comment on the line before its fence (invisible
on GitHub and in the built site)::

    <!-- command-test: KEY=VALUE ... -->

with, shell-quoted:

* ``replace="OLD=>NEW"`` (repeatable): the small-input variant, a literal substitution in
  the block (``make study`` as a dry run of the thesis study: its config validated and its
  jobs planned; ``tests/test_workflow.py`` runs a whole small study);
* ``append="ARGS"``: ARGS added to every ``ssw`` command of the block (``--config
  config/ci.yaml``: the small study's coarser mesh);
* ``fixture=NAME`` (repeatable): inputs the block needs, made first by the public commands
  (:data:`FIXTURES`): the README's own device, reference recordings, a calibration;
* ``slow``: the block runs with ``-m slow`` only (minutes as written);
* ``xfail="REASON"``: a known failure, strict (the test fails once the command works, so
  the marker goes);
* ``norun="REASON"``: not run here, and why (another test runs it).

A block runs with ``bash -e -o pipefail`` in a fresh copy of the repository (its tracked
files, ``.venv`` linked to the running interpreter's environment), with that environment's
``bin`` first on PATH, as after ``. .venv/bin/activate``, and without the test suite's
``SSW_CALIBRATION=none`` (a fresh clone has no study results). ``make`` runs as ``make -o
setup``: the set-up is the one the suite itself runs under (``make test`` sets up first).
``docs/cluster.md`` (Slurm; ``tests/test_slurm.py``) and ``docs/CONTRACTS.md`` (no commands)
are not read. Identical blocks (comments aside) run once.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
VENV = Path(sys.prefix)
SOURCES = ["README.md", *sorted(
    str(p.relative_to(ROOT)) for p in (ROOT / "docs").rglob("*.md")
    if "_build" not in p.parts and p.name not in {"cluster.md", "CONTRACTS.md"}
)]
SHELLS = {"sh", "bash", "shell", "console"}
_FENCE = re.compile(r"^```(\w*)\s*$")
_MARKER = re.compile(r"^<!--\s*command-test:(.*?)-->\s*$")
#: Wall-clock bound of one block, s (a hang must fail, not stall the suite); a slow block
#: runs its commands as written, minutes each on a loaded machine.
TIMEOUT_S = 900
SLOW_TIMEOUT_S = 3600


@dataclass
class Block:
    """One shell block of a page: where it is, its text and its marker's settings."""

    source: str
    line: int
    text: str
    marked: bool
    options: dict[str, list[str]] = field(default_factory=dict)

    def opt(self, key: str) -> str | None:
        values = self.options.get(key)
        return values[-1] if values else None

    def script(self) -> str:
        """The block as it runs: small-input variant applied."""
        text = self.text
        for rule in self.options.get("replace", []):
            old, new = rule.split("=>", 1)
            assert old in text, f"{self.where}: replace target {old!r} is not in the block"
            text = text.replace(old, new)
        text = text.replace("\\\n", " ")
        append = self.opt("append")
        lines = []
        for ln in text.splitlines():
            code, _, comment = ln.partition(" #")
            if append and code.lstrip().startswith("ssw "):
                ln = f"{code.rstrip()} {append}" + (f"  #{comment}" if comment else "")
            ln = re.sub(r"^(\s*)make ", r"\1make -o setup ", ln)
            lines.append(ln)
        return "\n".join(lines) + "\n"

    @property
    def where(self) -> str:
        return f"{self.source}:{self.line}"

    @property
    def key(self) -> str:
        """What the block runs (comments and blank lines aside) and with which inputs."""
        body = [ln.split(" #")[0].rstrip() for ln in self.script().splitlines()
                if ln.strip() and not ln.lstrip().startswith("#")]
        return "\n".join(body) + "|" + ",".join(sorted(self.options.get("fixture", [])))


def parse_marker(text: str) -> dict[str, list[str]]:
    """``KEY=VALUE`` and bare ``KEY`` tokens of a marker, shell-quoted."""
    out: dict[str, list[str]] = {}
    for token in shlex.split(text):
        key, _, value = token.partition("=")
        out.setdefault(key, []).append(value)
    return out


def blocks_of(source: str) -> list[Block]:
    """The shell blocks of one page, with their markers."""
    lines = (ROOT / source).read_text().splitlines()
    out: list[Block] = []
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        lang, start = m.group(1), i
        i += 1
        while i < len(lines) and not lines[i].startswith("```"):
            i += 1
        if lang in SHELLS:
            prev = lines[start - 1] if start else ""
            marker = _MARKER.match(prev)
            out.append(Block(source, start + 1, "\n".join(lines[start + 1:i]) + "\n",
                             marker is not None,
                             parse_marker(marker.group(1)) if marker else {}))
        i += 1
    return out


ALL = [b for s in SOURCES for b in blocks_of(s)]


def _unique(blocks: list[Block]) -> list[Block]:
    seen: dict[str, Block] = {}
    for b in blocks:
        if b.marked and "norun" not in b.options:
            seen.setdefault(b.key, b)
    return list(seen.values())


def _param(b: Block):
    marks = []
    if "slow" in b.options:
        marks.append(pytest.mark.slow)
    if b.opt("xfail") is not None:
        marks.append(pytest.mark.xfail(reason=b.opt("xfail"), strict=True))
    return pytest.param(b, id=b.where, marks=marks)


# ---------------------------------------------------------------------------- fixtures


def run_group(cmd: list[str], cwd: Path, env: dict[str, str],
              timeout: float) -> subprocess.CompletedProcess:
    """Run ``cmd`` in its own process group; on timeout kill the whole group (a command's
    worker processes included) and report the timeout as exit status -9."""
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        err += f"\n[timed out after {timeout:.0f} s]"
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def _run(cmd: list[str], cwd: Path, env: dict[str, str]) -> None:
    r = run_group(cmd, cwd, env, TIMEOUT_S)
    assert r.returncode == 0, f"{cmd}: exit {r.returncode}\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"


#: One process running ``ssw`` commands one after the other, as ``ssw`` runs each (the
#: console script's ``ssw.cli.main``), stopping at the first that fails: the fixtures' many
#: acquisitions pay the interpreter's start and ssw's imports once (about 2 s a command).
_SSW_EACH = """
import json, sys
from ssw.cli import main
for argv in json.loads(sys.argv[1]):
    rc = main(argv)
    if rc:
        sys.exit(f"ssw {' '.join(argv)}: exit {rc}")
"""


def _ssw_each(commands: list[list[str]], cwd: Path, env: dict[str, str]) -> None:
    """Run the ``ssw`` commands (argv without ``ssw``) in one process, in order."""
    import json

    _run([sys.executable, "-c", _SSW_EACH, json.dumps(commands)], cwd, env)


def _acquire(out: str, material: str, seed: int) -> list[str]:
    """The README's ``ssw acquire`` of a simulated session of 3 hits (argv without ``ssw``)."""
    return ["acquire", "--simulate", "--sample", out.removesuffix(".h5"), "--material",
            material, "--hits", "3", "--seed", str(seed), "--output", out, "--device",
            "my_device.yaml", "--calibration", "none"]


def make_device(d: Path, env: dict[str, str]) -> None:
    """The README's device (a copy of the thesis's), simulated recordings of three
    references of known modulus (the Sawbones foams) and of a test point (PCF 15)."""
    shutil.copy(ROOT / "config" / "devices" / "thesis.yaml", d / "my_device.yaml")
    _ssw_each([_acquire(name, material, seed) for name, material, seed in [
        ("ref_soft.h5", "pcf08", 1), ("ref_mid.h5", "pcf15", 2), ("ref_stiff.h5", "pcf30", 3),
        ("point7_1.h5", "pcf15", 4), ("point7_2.h5", "pcf15", 5)]], d, env)


def make_calibration(d: Path, env: dict[str, str]) -> None:
    """``my_calibration.json``: the README's step 2 with its free parameters named (the
    striker speed and the static load)."""
    _run(["ssw", "calibrate", "--device", "my_device.yaml",
          "--reference-recording", "ref_soft.h5,38e6,0.34",
          "--reference-recording", "ref_mid.h5,123e6,0.33",
          "--reference-recording", "ref_stiff.h5,445e6,0.30",
          "--free", "striker_velocity", "--free", "preload",
          "--calibration", "none", "--output", "my_calibration.json"], d, env)


def make_recordings(d: Path, env: dict[str, str]) -> None:
    """Two recordings of one point in two formats: ssw's HDF5 and NI TDMS."""
    shutil.copy(ROOT / "config" / "devices" / "thesis.yaml", d / "my_device.yaml")
    _ssw_each([_acquire("rec1.h5", "pcf15", 6), _acquire("rec2.h5", "pcf15", 7)], d, env)
    _run([sys.executable, "-c", "from ssw.daq.importers import read_any, write_any; "
          "write_any('rec2.tdms', read_any('rec2.h5'))"], d, env)
    (d / "rec2.h5").unlink()
    (d / "my_device.yaml").unlink()


#: Fixture name -> (maker, fixtures it needs first).
FIXTURES = {
    "device": (make_device, ()),
    "calibration": (make_calibration, ("device",)),
    "recordings": (make_recordings, ()),
}


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(VENV / "bin"), env.get("PATH", "")])
    env["VIRTUAL_ENV"] = str(VENV)
    env.pop("SSW_CALIBRATION", None)
    return env


def _copy_repository(dest: Path) -> None:
    skip = {".venv", ".git", "results", ".snakemake", "build", "_build", ".pytest_cache",
            ".ruff_cache", "__pycache__", "ssw.egg-info"}
    shutil.copytree(ROOT, dest, ignore=lambda d, names: [n for n in names if n in skip])
    (dest / ".venv").symlink_to(VENV)


@pytest.fixture(scope="session")
def made(tmp_path_factory):
    """Fixture name -> folder of its files, each made once per session."""
    done: dict[str, Path] = {}
    env = _env()

    def get(name: str) -> Path:
        if name not in done:
            maker, needs = FIXTURES[name]
            d = tmp_path_factory.mktemp(f"fixture-{name}")
            for need in needs:
                shutil.copytree(get(need), d, dirs_exist_ok=True)
            maker(d, env)
            done[name] = d
        return done[name]

    return get


# ---------------------------------------------------------------------------- tests


def test_every_shell_block_is_marked():
    """A shell block without a marker would drift unseen: each says how it is tested."""
    unmarked = [b.where for b in ALL if not b.marked]
    assert not unmarked, f"shell blocks without a <!-- command-test: ... --> marker: {unmarked}"
    for b in ALL:
        unknown = set(b.options) - {"replace", "append", "fixture", "slow", "xfail", "norun"}
        assert not unknown, f"{b.where}: unknown marker keys {sorted(unknown)}"
        for name in b.options.get("fixture", []):
            assert name in FIXTURES, f"{b.where}: unknown fixture {name!r}"
        b.script()  # every replace target is in its block


def test_the_readme_commands_run_by_default():
    """The README's commands are part of the default suite (none slow, none skipped)."""
    readme = [b for b in ALL if b.source == "README.md"]
    assert readme
    assert not [b.where for b in readme if "slow" in b.options]


def test_a_marker_changes_what_runs():
    """The small-input variant is what runs (a check of the harness itself)."""
    b = Block("x.md", 1, "make study   # the study\nssw tof --soil-E 1e7 \\\n    --json\n",
              True, {"replace": ["make study=>make study CONFIG=config/ci.yaml"],
                     "append": ["--config config/ci.yaml"]})
    assert b.script() == ("make -o setup study CONFIG=config/ci.yaml   # the study\n"
                          "ssw tof --soil-E 1e7      --json --config config/ci.yaml\n")


@pytest.mark.parametrize("block", [_param(b) for b in _unique(ALL)])
def test_command_block_runs(block: Block, made, tmp_path):
    work = tmp_path / "repo"
    _copy_repository(work)
    for name in block.options.get("fixture", []):
        shutil.copytree(made(name), work, dirs_exist_ok=True)
    script = block.script()
    timeout = SLOW_TIMEOUT_S if "slow" in block.options else TIMEOUT_S
    r = run_group(["bash", "-e", "-o", "pipefail", "-c", script], work, _env(), timeout)
    assert r.returncode == 0, (
        f"{block.where} exited {r.returncode}:\n{script}\n--- stdout\n{r.stdout[-4000:]}"
        f"\n--- stderr\n{r.stderr[-4000:]}")

"""Shared fixtures of the test suite."""

from __future__ import annotations

import itertools
import os
import signal
import sys

import pytest

# one BLAS thread, as ssw itself sets (ssw/__init__.py): set before any test imports numpy
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
# the repository's own study results (after `make study`) must not change what a test's
# command computes: commands default to the uncalibrated device (--calibration none) unless
# a test names a calibration; the workflow's rules always pass --calibration explicitly
os.environ["SSW_CALIBRATION"] = "none"


# ---------------------------------------------------------------- the suite on several cores
# `make test` runs pytest-xdist with `--dist loadgroup --no-loadscope-reorder`: tests of one
# xdist group run on one worker, one after the other, and the groups leave in the order of
# the collection. pytest_collection_modifyitems below puts into one group (the union of):
# * the tests that share a fixture wider than a test (module, class or session scope, defined
#   in tests/): such a fixture is computed once, not once per worker (but `ci_study`, a
#   whole study, is shared by the workers through a file lock: its tests spread);
# * the tests that share a machine-wide resource (the local Slurm cluster and its job names;
#   `mpiexec -n 2` runs, which busy-wait when they share the 2 cores with one another).
# and moves the tests, groups and modules of EARLY to the front, longest first: a long one
# that starts last leaves the other worker idle at the end. The two longest tests lead, one
# on each worker: xdist hands the first unit to the first worker and the second to the
# second, then one more unit to each (a worker gets more once at most 2 of its tests wait).

#: Markers whose tests share one machine-wide resource (one group each).
SHARED_MARKERS = ("slurm", "mpi")
#: Session fixtures computed once per run across the workers (a file lock): no group.
LOCKED_FIXTURES = ("ci_study",)
#: Dispatched first, longest first: single tests (a node id), groups (named by a member's
#: key: a marker, ``fixture:NAME`` or a module's path) and modules (a path: its tests that are
#: in no group). From ``pytest -n 2 --durations=0`` (2 cores, 2026-11-29): the two longest
#: tests (113 s and 117 s of the 523 s run), then modules' and groups' seconds.
EARLY = (
    "tests/test_honesty.py::test_the_as_built_device_is_honest_small",  # the study's variant
    "tests/test_docs.py",  # the documentation site, from nothing in a fresh clone
    "slurm",  # the lost-jobs, pending and Ctrl-C tests' waits
    "tests/test_workflow.py",  # the CI study (ci_study) and the tests that read it
    "fixture:made", "tests/test_commands.py",  # the README's and the docs' commands
    "tests/test_calibration.py",
    "tests/test_contact_plastic.py",
    "tests/test_measure_information.py",
    "tests/test_calibration_flags.py",
    "tests/test_design_cli.py",
    "tests/test_interrupt.py",
    "tests/test_dynamic.py",
    "tests/test_workflow_reruns.py",
    "tests/test_design_device_plastic.py",
    "tests/test_plastic_wall.py",
    "tests/test_design_device_workflow.py",
)


def _group_keys(item: pytest.Item) -> list[str]:
    """What ``item`` shares with other tests: its markers of SHARED_MARKERS and its fixtures
    wider than a test that tests/ defines (``fixture:NAME`` for session scope, the module's
    path for module and class scope)."""
    keys = [m for m in SHARED_MARKERS if item.get_closest_marker(m) is not None]
    info = getattr(item, "_fixtureinfo", None)
    for name, defs in (info.name2fixturedefs.items() if info else ()):
        fdef = defs[-1]
        if not fdef.baseid.startswith("tests"):  # pytest's own (tmp_path_factory ...)
            continue
        if fdef.scope == "session":
            if name not in LOCKED_FIXTURES:
                keys.append(f"fixture:{name}")
        elif fdef.scope in ("module", "class", "package"):
            keys.append(item.nodeid.split("::")[0])
    return keys


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark the tests that share an expensive fixture or a machine-wide resource with one
    ``xdist_group`` per connected set (before xdist reads the marks), and order the items:
    those of EARLY first, in its order (a test by its node id, else by its group or its
    module), then the rest in collection order."""
    parent: dict[str, str] = {}

    def find(k: str) -> str:
        while parent.setdefault(k, k) != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    keys = {item.nodeid: _group_keys(item) for item in items}
    for ks in keys.values():
        for a, b in itertools.pairwise(ks):
            parent[find(b)] = find(a)
    size: dict[str, int] = {}
    for ks in keys.values():
        if ks:
            size[find(ks[0])] = size.get(find(ks[0]), 0) + 1
    group: dict[str, str] = {}
    for item in items:
        ks = keys[item.nodeid]
        if ks and size[find(ks[0])] > 1:
            group[item.nodeid] = find(ks[0])
            item.add_marker(pytest.mark.xdist_group(find(ks[0])))
    rank = {name: i for i, name in enumerate(EARLY)}
    items.sort(key=lambda it: rank.get(it.nodeid, rank.get(
        group.get(it.nodeid) or it.nodeid.split("::")[0], len(rank))))


def pytest_collection_finish(session: pytest.Session) -> None:
    """On an xdist worker under ``--dist loadgroup``: stop when xdist did not tag a grouped
    test's id with its group (then it spreads the group over the workers without a word: a
    session fixture computed once per worker, Slurm tests side by side), as with pytest 9.2
    (constraints.txt)."""
    if not getattr(session.config.option, "loadgroup", False):
        return
    lost = [it.nodeid for it in session.items
            if it.get_closest_marker("xdist_group") and "@" not in it.nodeid]
    if lost:
        msg = (f"pytest-xdist's --dist loadgroup did not group {len(lost)} tests (e.g. "
               f"{lost[0]}): pytest {pytest.__version__} with this pytest-xdist; use the "
               "versions of constraints.txt")
        print(f"ERROR: {msg}", file=sys.__stderr__, flush=True)  # a worker's error is terse
        raise pytest.UsageError(msg)


@pytest.fixture
def no_hang(request):
    """Fail a case that runs longer than its module's ``CASE_TIMEOUT_S`` seconds (default 120)
    with TimeoutError: a hang must fail, not stall the suite (SIGALRM; no pytest-timeout here).
    Stress modules use it with ``pytestmark = pytest.mark.usefixtures("no_hang")``."""
    limit = int(getattr(request.module, "CASE_TIMEOUT_S", 120))

    def expire(signum, frame):
        raise TimeoutError(f"case exceeded {limit} s: a hang")

    old = signal.signal(signal.SIGALRM, expire)
    signal.alarm(limit)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


def require(ok: bool, reason: str) -> None:
    """Skip a test whose tool is missing here, but fail it in CI (``CI=true``), where every
    tool is installed by the set-up: a missing one there is a broken set-up, not a pass."""
    if ok:
        return
    if os.environ.get("CI") == "true":
        pytest.fail(f"{reason} (CI=true: the set-up must provide it)")
    pytest.skip(reason)


@pytest.fixture(scope="session")
def ci_study(tmp_path_factory):
    """The whole pipeline on config/ci.yaml, run once for the session: contact -> fits -> the
    fem wall -> calibration on the thesis foams' measured TOFs -> sweep -> Tables 2-3 ->
    survey. Tests read it or dry-run edits against it; a test that reruns jobs copies it.

    Once for the whole run under pytest-xdist too: in the run's folder, which its workers
    share, under a file lock; the first worker that needs it runs it, another that needs it
    meanwhile waits for it (so its tests need no xdist group)."""
    import fcntl
    import shutil

    from snakemake_run import ROOT, smk

    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the run's folder: the workers' own folders are in it
    tmp, done = base / "ci_study", base / "ci_study.complete"
    with open(base / "ci_study.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.is_file():
            shutil.rmtree(tmp, ignore_errors=True)
            shutil.copytree(ROOT / "config", tmp / "config")
            r = smk("--cores", "2", "--directory", str(tmp), "--configfile",
                    str(tmp / "config" / "ci.yaml"), timeout=900)
            assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-4000:]
            done.touch()
    return tmp


def run_device_design(d, space: dict, *flags: str) -> dict:
    """``ssw design --space device`` on the study config with the device space ``space``
    (written to ``d``/config.yaml), 20-200 MPa at nu 0.3, a sample yield limit of 50, the
    output in ``d``/design.json and .csv, plus ``flags``; its JSON."""
    import json
    from pathlib import Path

    import yaml

    from ssw.cli import main

    root = Path(__file__).resolve().parent.parent
    cfg = yaml.safe_load((root / "config" / "config.yaml").read_text())
    cfg.setdefault("design", {})["device"] = space
    (d / "config.yaml").write_text(yaml.safe_dump(cfg))
    out = d / "design.json"
    assert main(["design", "--space", "device", "--config", str(d / "config.yaml"),
                 "--calibration", "none", "--soil-E", "20e6:200e6", "--soil-nu", "0.3",
                 "--soil-yield-limit", "50", "--output", str(out), "--csv",
                 str(d / "design.csv"), *flags]) == 0
    return json.loads(out.read_text())

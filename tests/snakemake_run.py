"""Running the study's Snakefile from the tests: the environment of a user, job counts."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))


def user_env() -> dict[str, str]:
    """The environment of a user who has not activated .venv: its bin is NOT on PATH (the
    workflow must find `python -m ssw` through the interpreter that runs Snakemake)."""
    env = dict(os.environ)
    venv_bin = str(Path(sys.executable).parent)
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                  if p and p != venv_bin)
    env.pop("VIRTUAL_ENV", None)
    return env


def smk(*args: str, cwd: Path = ROOT, timeout: float = 600) -> subprocess.CompletedProcess:
    """`snakemake -s <repository Snakefile> ARGS` as a user runs it."""
    return subprocess.run([SNAKEMAKE, "-s", str(ROOT / "workflow" / "Snakefile"), *args], cwd=cwd,
                          capture_output=True, text=True, env=user_env(), timeout=timeout)


def job_stats(text: str) -> dict[str, int]:
    """Rule -> job count from Snakemake's 'Job stats' table ({} when nothing is to be done)."""
    if "Job stats:" not in text:
        return {}
    table = text.split("Job stats:")[1]
    return {m.group(1): int(m.group(2))
            for m in re.finditer(r"^(\w+)\s+(\d+)\s*$", table, re.MULTILINE)}

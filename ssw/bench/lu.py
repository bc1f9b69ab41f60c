"""``ssw bench lu``: every sparse factorization ssw makes, by every factorization package.

The matrices are recorded from the code paths that factor them (the study config's contact
settings, 50 MPa soil, nu 0.3; the PLA plate of the library):

* ``monolithic``: the whole u-p matrix of a scene, ``engine="monolithic"``, without a plate
  and with the 0.4 mm PLA plate; today PETSc's LU in the natural order of the
  nested-dissection numbering, no pivoting (:mod:`ssw.contact.petsc_solver`);
* ``dynamic``: the dynamic FEM wall's Newmark matrix ``K + 4/dt^2 M + 2/dt C``
  (:mod:`ssw.dynamics.newmark`, same LU) of the thesis device on that soil;
* ``schur``: the substructured engine's body matrices (soil without a plate, plate and soil
  with it), condensed onto their retained dofs by the trailing block of a pivot-free
  SuperLU (scipy) in minimum-degree order (:func:`ssw.contact.substructure.schur_complement`);
  the alternatives factor ``K_II`` and solve ``K_IB``: ``S = K_BB - K_BI K_II^-1 K_IB``;
* ``plastic``: the plastic solver's first (elastic) and last Newton matrices of a von Mises
  loading on the same mesh (``ssw bench plastic``'s sample: 38 MPa, nu 0.34, yield 1.4
  MPa; :mod:`ssw.contact.plastic`: SuperLU, minimum degree on ``A + A^T``, diagonal
  pivots).

Each is factored by the method in use (``current``) and by
:class:`ssw.contact.petsc_solver.LUSolver` with PETSc's own LU (natural order; nested
dissection), MUMPS and SuperLU_DIST (those order and pivot by themselves), where the PETSc
build has them. Columns: the factorization's wall and CPU time (for LUSolver the COO
assembly included, as ssw pays it), one solve with one right-hand side and one with a block
of ``--block`` (the condensation's columns), and the backward error ``||A X - B|| / (||A||
||X|| + ||B||)`` of the block (of the single solve for ``plastic``); for ``schur`` the
whole condensation's time and the largest difference to today's ``S`` relative to its
largest entry. Wall times are the best of ``--repeat``.

Measured 2026-11-26 on 2 cores (shared, load 5-8: CPU times in parentheses are the
comparison; binary stack, PETSc 3.25.5) with ``ssw bench lu --repeat 3``:

* monolithic u-p (18 735 and 27 964 dofs): MUMPS factors in 0.15/0.25 s CPU against
  PETSc's 0.19/0.39 s and solves a block of 64 in 0.06/0.09 s against 0.16/0.29 s,
  backward errors 1e-20 both; the whole curve (1000 increments) 0.49/0.59 s CPU against
  0.66/0.87 s (wall 0.98/1.11 s against 1.31/1.73 s), forces equal within 7e-11: the
  monolithic engine switched to MUMPS (``LUSolver(solver="auto")``);
* dynamic u-p (18 870 dofs): MUMPS factors faster (0.17 against 0.24 s) but solves one
  right-hand side slower (5.9 against 3.5 ms), and a wall steps thousands of such solves:
  PETSc's natural-order LU stays;
* Schur complements (112-231 retained dofs): today's trailing block of SuperLU takes
  0.08-0.10 s CPU, the fastest alternative (MUMPS, factor and solve) 0.22-0.33 s: stays;
* plastic Newton matrices (18 735 dofs): SuperLU factors in 0.10-0.11 s and solves in
  3.8 ms, MUMPS 0.11 s and 5.8-6.0 ms, SuperLU_DIST 0.11 s and 6.4-6.5 ms, PETSc
  (nested dissection) 0.16 s and 3.4 ms: SuperLU stays.

Writes ``lu_bench.csv`` and ``lu_bench.json`` under the output folder.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ssw.h5io import atomic_write_text, write_json

#: Right-hand sides of the block solve (the order of a scene's condensed candidates).
BLOCK = 64
#: Solves per timing round of a single right-hand side (a time step's solve is short).
SOLVES = 10
#: Soil of the recorded scenes: E Pa, nu, density kg/m^3.
SOIL = (50e6, 0.3, 1800.0)
#: Increments of the recorded curves (only their matrices are used).
STEPS = 20
#: The PETSc variants of each matrix: (label, solver, ordering).
VARIANTS = (("petsc natural", "petsc", "natural"), ("petsc nd", "petsc", "nd"),
            ("mumps", "mumps", None), ("superlu_dist", "superlu_dist", None))


def register(kinds: argparse._SubParsersAction) -> None:
    """Add the ``ssw bench lu`` command and its options.

    Parameters
    ----------
    kinds : argparse._SubParsersAction
        The ``ssw bench`` subcommands.
    """
    p = kinds.add_parser("lu", help="every sparse factorization ssw makes, by every package")
    p.add_argument("--matrices", nargs="+", default=["monolithic", "dynamic", "schur", "plastic"],
                   choices=["monolithic", "dynamic", "schur", "plastic"],
                   help="which matrices to record and factor")
    p.add_argument("--repeat", type=int, default=3,
                   help="timings per measurement; the fastest is kept (shared machines)")
    p.add_argument("--block", type=int, default=BLOCK,
                   help="right-hand sides of the block solve")
    p.add_argument("--output-dir", default="results/bench", help="folder of the outputs")
    p.add_argument("--config", default="config/config.yaml", help="study config (YAML)")
    p.set_defaults(func=run, human=human)


@dataclass(frozen=True)
class Recorded:
    """A matrix as a code path handed it to its factorization.

    Parameters
    ----------
    matrix : str
        Its name in the table.
    kind : str
        ``lu`` (COO triplets for LUSolver), ``schur`` (``K`` with ``n_int`` interior dofs)
        or ``plastic`` (the CSC of the Newton matrix's transpose, as splu gets it).
    data : tuple
        ``(rows, cols, vals, n, scale)`` for ``lu``, ``(K, n_int)`` for ``schur``,
        ``(A_T,)`` for ``plastic``.
    """

    matrix: str
    kind: str
    data: tuple


@contextmanager
def recording() -> Iterator[list[tuple[str, tuple, dict]]]:
    """Record the arguments of every factorization ssw makes while in the block.

    Yields
    ------
    list of tuple
        ``(where, args, kwargs)`` appended per call: ``where`` is ``monolithic``,
        ``dynamic``, ``schur`` or ``plastic``.
    """
    from unittest import mock

    import ssw.contact.plastic_model as plastic
    import ssw.contact.scene as scene
    import ssw.contact.substructure as sub
    import ssw.dynamics.newmark as newmark

    calls: list[tuple[str, tuple, dict]] = []

    def spy(where: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def wrapped(*args: Any, **kwargs: Any) -> Any:
            calls.append((where, args, kwargs))
            return fn(*args, **kwargs)
        return wrapped

    with mock.patch.object(scene, "LUSolver", spy("monolithic", scene.LUSolver)), \
            mock.patch.object(newmark, "LUSolver", spy("dynamic", newmark.LUSolver)), \
            mock.patch.object(sub, "schur_complement", spy("schur", sub.schur_complement)), \
            mock.patch.object(plastic, "_factor", spy("plastic", plastic._factor)):
        yield calls


def record_matrices(cfg: dict[str, Any], which: list[str]) -> list[Recorded]:
    """Run the code paths of ``which`` (module docstring) and keep their matrices.

    Parameters
    ----------
    cfg : dict
        The study config.
    which : list of str
        Matrix kinds: ``monolithic``, ``dynamic``, ``schur``, ``plastic``.

    Returns
    -------
    list of Recorded
        The matrices, in the order of the module docstring.
    """
    from ssw.config import library
    from ssw.contact import solve_curve
    from ssw.contact.operators import OperatorStore

    E, nu, rho = SOIL
    radius = float(cfg["indenter"]["radius"])
    contact = {**cfg["contact"], "steps": STEPS, "delta_mode": "fixed"}
    contact.pop("delta_reach", None)
    pla = library(cfg)["pla"]
    plates = (("no plate", None, 0.0), ("PLA 0.4 mm", (pla.E, pla.nu), 0.4e-3))
    out: list[Recorded] = []
    if "monolithic" in which:
        for label, plate, t in plates:
            with recording() as calls:
                _, state = solve_curve((E, nu), plate, t, radius, contact, engine="monolithic")
                state["solver"].destroy()
            args = calls[0][1]
            out.append(Recorded(f"monolithic u-p, {label}", "lu", tuple(args[:5])))
    if "dynamic" in which:
        from ssw.chain.params import ChainParams
        from ssw.dynamics.fem_wall import fem_wall

        with recording() as calls:
            wall, _ = fem_wall(ChainParams.from_config(cfg), E, nu, rho)
            wall.destroy()
        args = calls[-1][1]  # the Newmark matrix (the static one comes first)
        out.append(Recorded("dynamic u-p (Newmark), the config's device", "lu",
                            tuple(args[:5])))
    if "schur" in which:
        for label, plate, t in plates:
            with recording() as calls:
                solve_curve((E, nu), plate, t, radius, contact, OperatorStore(None))
            largest = max(args[0].shape[0] for _, args, _ in calls)
            for _, args, _ in calls:  # the soil is the larger body
                body = "soil" if args[0].shape[0] == largest else "plate"
                out.append(Recorded(f"schur, {body}, {label}", "schur", tuple(args)))
    if "plastic" in which:
        from ssw.constitutive import VonMises
        from ssw.contact.plastic import solve_plastic_scene

        with recording() as calls:
            solve_plastic_scene((38e6, 0.34), VonMises(1.4e6), radius, contact)
        out.append(Recorded("plastic Newton, elastic", "plastic", tuple(calls[0][1])))
        out.append(Recorded("plastic Newton, last", "plastic", tuple(calls[-1][1])))
    return out


def _timed(fn: Callable[[], Any], repeat: int, inner: int = 1) -> tuple[float, float, Any]:
    """Fastest wall time and fastest CPU time (s, per call, each over ``repeat`` rounds of
    ``inner`` calls: on a shared machine, noise only adds time) and the last result."""
    wall, cpu, out = float("inf"), float("inf"), None
    for _ in range(max(1, int(repeat))):
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(inner):
            out = fn()
        wall = min(wall, (time.perf_counter() - t0) / inner)
        cpu = min(cpu, (time.process_time() - c0) / inner)
    return wall, cpu, out


def _row(rec: Recorded, n: int, nnz: int, method: str, **fields: Any) -> dict[str, Any]:
    base = {"matrix": rec.matrix, "n": n, "nnz": nnz, "method": method, "factor_wall": None,
            "factor_cpu": None, "solve_wall": None, "solve_cpu": None, "block_wall": None,
            "block_cpu": None, "backward_error": None, "schur_difference": None, "note": ""}
    return {**base, **fields}


def _petsc_lu(rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, n: int, scale: float,
              solver: str, ordering: str | None, repeat: int, block: int,
              rng: np.random.Generator) -> dict[str, Any]:
    """Factor and solve with :class:`LUSolver`; a failure is a note, not an error."""
    from ssw.contact.petsc_solver import LUSolver, backward_error
    from ssw.errors import SolverError

    def make() -> Any:
        return LUSolver(rows, cols, vals, n, scale, solver=solver, ordering=ordering,
                        parallel=False)

    try:
        lus: list[Any] = []
        wall, cpu, lu = _timed(lambda: lus.append(make()) or lus[-1], repeat)
        for other in lus[:-1]:
            other.destroy()
        b = rng.uniform(-1.0, 1.0, n)
        B = rng.uniform(-1.0, 1.0, (n, block))
        lu.solve(b)  # the first solve checks the backward error
        t1, c1, _ = _timed(lambda: lu.solve(b), repeat, SOLVES)
        tb, cb, X = _timed(lambda: lu.solve(B), repeat)
        berr = backward_error((rows, cols, vals), n, X * scale, B)
        lu.destroy()
    except SolverError as exc:
        return {"note": f"failed: {exc}"}
    return {"factor_wall": wall, "factor_cpu": cpu, "solve_wall": t1, "solve_cpu": c1,
            "block_wall": tb, "block_cpu": cb, "backward_error": berr}


def _lu_rows(rec: Recorded, repeat: int, block: int, solvers: tuple[str, ...]
             ) -> list[dict[str, Any]]:
    rows, cols, vals, n, scale = rec.data
    import scipy.sparse as sp

    nnz = sp.coo_array((vals, (rows, cols)), shape=(n, n)).tocsr().nnz
    out = []
    for label, solver, ordering in VARIANTS:
        if solver not in solvers:
            continue
        rng = np.random.default_rng(0)
        res = _petsc_lu(rows, cols, vals, n, scale, solver, ordering, repeat, block, rng)
        method = label + (" (current)" if label == "petsc natural" else "")
        out.append(_row(rec, n, nnz, method, **res))
    return out


def _schur_rows(rec: Recorded, repeat: int, solvers: tuple[str, ...]) -> list[dict[str, Any]]:
    """Today's condensation against factor-K_II-and-solve-K_IB by each package."""
    import scipy.sparse as sp

    from ssw.contact.petsc_solver import LUSolver, backward_error
    from ssw.contact.substructure import schur_complement
    from ssw.errors import SolverError

    K, n_int = rec.data
    K = sp.csc_array(K)
    n, nb = K.shape[0], K.shape[0] - n_int
    wall, cpu, (S_ref, berr, _, pivoted) = _timed(lambda: schur_complement(K, n_int), repeat)
    note = f"{nb} retained dofs" + (", pivoted fallback" if pivoted else "")
    out = [_row(rec, n, int(K.nnz), "scipy SuperLU trailing block (current)", factor_wall=wall,
                factor_cpu=cpu, backward_error=berr, schur_difference=0.0, note=note)]
    KII = sp.coo_array(K[:n_int, :n_int])
    KIB = K[:n_int, n_int:].toarray()
    KBI, KBB = K[n_int:, :n_int], K[n_int:, n_int:].toarray()
    for label, solver, ordering in VARIANTS:
        if solver not in solvers:
            continue

        def condense(solver: str = solver, ordering: str | None = ordering) -> Any:
            lu = LUSolver(KII.row, KII.col, KII.data, n_int, solver=solver, ordering=ordering,
                          parallel=False)
            X = lu.solve(KIB)
            lu.destroy()
            return X, KBB - KBI @ X

        try:
            wall, cpu, (X, S) = _timed(condense, repeat)
        except SolverError as exc:
            out.append(_row(rec, n, int(K.nnz), label, note=f"failed: {exc}"))
            continue
        diff = float(np.max(np.abs(S - S_ref)) / np.max(np.abs(S_ref)))
        out.append(_row(rec, n, int(K.nnz), label, factor_wall=wall, factor_cpu=cpu,
                        backward_error=backward_error((KII.row, KII.col, KII.data), n_int, X,
                                                      KIB),
                        schur_difference=diff, note=note))
    return out


def _plastic_rows(rec: Recorded, repeat: int, solvers: tuple[str, ...]
                  ) -> list[dict[str, Any]]:
    """Today's SuperLU of a Newton matrix against each package."""
    import scipy.sparse as sp

    from ssw.contact.petsc_solver import backward_error
    from ssw.contact.plastic_model import _factor

    (AT,) = rec.data
    A = sp.coo_array(AT.T)
    n = A.shape[0]
    coo = (A.row, A.col, A.data)
    b = np.random.default_rng(0).uniform(-1.0, 1.0, n)
    wall, cpu, lu = _timed(lambda: _factor(AT), repeat)
    ts, cs, x = _timed(lambda: lu.solve(b, trans="T"), repeat, SOLVES)
    out = [_row(rec, n, int(A.nnz), "scipy SuperLU MMD(A+A^T) (current)", factor_wall=wall,
                factor_cpu=cpu, solve_wall=ts, solve_cpu=cs,
                backward_error=backward_error(coo, n, x, b))]
    for label, solver, ordering in VARIANTS:
        if solver not in solvers or ordering == "natural":  # not a fill-reducing numbering
            continue
        res = _petsc_lu(*coo, n, 1.0, solver, ordering, repeat, 1, np.random.default_rng(0))
        res.pop("block_wall", None)
        res.pop("block_cpu", None)
        out.append(_row(rec, n, int(A.nnz), label, **res))
    return out


def monolithic_curves(cfg: dict[str, Any], repeat: int, solvers: tuple[str, ...]
                      ) -> list[dict[str, Any]]:
    """The monolithic engine's whole curve (the config's increments) with each package:
    wall and CPU time, and the largest force difference to PETSc's natural-order LU
    relative to the largest force.

    Parameters
    ----------
    cfg : dict
        The study config.
    repeat : int
        Timings per curve; the fastest is kept.
    solvers : tuple of str
        The packages to time (of :data:`VARIANTS`).

    Returns
    -------
    list of dict
        One row per scene and package.
    """
    from unittest import mock

    import ssw.contact.scene as scene
    from ssw.config import library
    from ssw.contact import solve_curve

    E, nu, _ = SOIL
    radius = float(cfg["indenter"]["radius"])
    pla = library(cfg)["pla"]
    lu_class = scene.LUSolver
    rows = []
    for label, plate, t in (("no plate", None, 0.0), ("PLA 0.4 mm", (pla.E, pla.nu), 0.4e-3)):
        ref = None
        for name, solver, ordering in VARIANTS:
            if solver not in solvers or name == "petsc nd":
                continue

            def forced(*a: Any, _use: tuple = (solver, ordering), **k: Any) -> Any:
                return lu_class(*a, **{**k, "solver": _use[0], "ordering": _use[1]})

            def curve(plate: Any = plate, t: float = t, forced: Any = forced) -> Any:
                with mock.patch.object(scene, "LUSolver", forced):
                    c, state = solve_curve((E, nu), plate, t, radius, cfg["contact"],
                                           engine="monolithic")
                state["solver"].destroy()
                return c

            wall, cpu, c = _timed(curve, repeat)
            ref = c.force if ref is None else ref
            rows.append({"scene": label, "method": name, "increments": int(c.delta.size),
                         "dofs": int(c.stats["dofs"]), "solves": int(c.stats["solves"]),
                         "wall": wall, "cpu": cpu,
                         "force_difference": float(np.max(np.abs(c.force - ref))
                                                   / np.max(np.abs(ref)))})
    return rows


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Run ``ssw bench lu`` (module docstring) and write ``lu_bench.csv`` and
    ``lu_bench.json`` under ``--output-dir``.

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (:func:`register`).

    Returns
    -------
    dict
        ``rows`` (per matrix and method: size, wall and CPU times in s, backward error),
        ``curves``, ``solvers``, ``petsc_version`` and the files written.
    """
    from ssw.config import load_config
    from ssw.contact.petsc_solver import _petsc, available_solvers

    cfg = load_config(args.config)
    solvers = available_solvers()
    recs = record_matrices(cfg, list(args.matrices))
    rows: list[dict[str, Any]] = []
    for rec in recs:
        if rec.kind == "lu":
            rows += _lu_rows(rec, args.repeat, args.block, solvers)
        elif rec.kind == "schur":
            rows += _schur_rows(rec, args.repeat, solvers)
        else:
            rows += _plastic_rows(rec, args.repeat, solvers)
    curves = (monolithic_curves(cfg, args.repeat, solvers) if "monolithic" in args.matrices
              else [])
    out = Path(args.output_dir)
    out.mkdir(parents=True, exist_ok=True)
    keys = list(rows[0])
    atomic_write_text(out / "lu_bench.csv", "\n".join(
        [",".join(keys)] + [",".join("" if r[k] is None else str(r[k]).replace(",", ";")
                                     for k in keys) for r in rows]) + "\n")
    version = ".".join(str(v) for v in _petsc().Sys.getVersion())
    res = {"rows": rows, "curves": curves, "solvers": list(solvers), "petsc_version": version,
           "outputs": [str(out / "lu_bench.csv"), str(out / "lu_bench.json")]}
    write_json(out / "lu_bench.json", res, {"matrices": list(args.matrices),
                                            "repeat": args.repeat, "block": args.block,
                                            "soil": SOIL, "steps": STEPS})
    return res


def _fmt(v: Any, spec: str) -> str:
    return "" if v is None else format(v, spec)


def human(res: dict[str, Any]) -> str:
    """The table as Markdown (times: wall s, CPU s in parentheses).

    Parameters
    ----------
    res : dict
        The result of :func:`run`.

    Returns
    -------
    str
        The PETSc version line and one table row per measurement.
    """
    def t(r: dict[str, Any], key: str, spec: str) -> str:
        w, c = r[f"{key}_wall"], r[f"{key}_cpu"]
        return "" if w is None else f"{w:{spec}} ({c:{spec}})"

    lines = [f"PETSc {res['petsc_version']}; packages: {', '.join(res['solvers'])}",
             "| matrix | n | nnz | method | factor s | solve s | block s | "
             "backward error | S diff | note |",
             "|---|---:|---:|---|---:|---:|---:|---:|---:|---|"]
    for r in res["rows"]:
        lines.append(
            f"| {r['matrix']} | {r['n']} | {r['nnz']} | {r['method']} | "
            f"{t(r, 'factor', '.3f')} | {t(r, 'solve', '.4f')} | {t(r, 'block', '.3f')} | "
            f"{_fmt(r['backward_error'], '.1e')} | {_fmt(r['schur_difference'], '.1e')} | "
            f"{r['note']} |")
    if res["curves"]:
        lines += ["", "monolithic engine, whole curve:",
                  "| scene | method | increments | dofs | solves | wall s (CPU s) | "
                  "force difference |", "|---|---|---:|---:|---:|---:|---:|"]
        lines += [f"| {c['scene']} | {c['method']} | {c['increments']} | {c['dofs']} | "
                  f"{c['solves']} | {c['wall']:.2f} ({c['cpu']:.2f}) | "
                  f"{c['force_difference']:.1e} |" for c in res["curves"]]
    lines.append("outputs: " + ", ".join(res["outputs"]))
    return "\n".join(lines)

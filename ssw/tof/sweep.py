"""TOF(E, nu) sweeps (thesis Fig 8): chunks for Snakemake jobs, MPI ranks, HDF5/CSV, plot.

A sweep is the product ``soil_E x soil_nu`` flattened nu-major (all E for the first nu,
then the next). Chunk ``c`` of ``C`` takes points ``c, c + C, c + 2C, ...`` (interleaved, so
that soft and stiff soils, whose runs differ in length, spread evenly); inside a job the
points are split the same way over MPI ranks when a communicator is given, and gathered on
every rank. Every point of a chunk advances in one batched run (:mod:`ssw.chain.integrate`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ssw.chain.params import ChainParams
from ssw.errors import ConfigError, SswError
from ssw.h5io import atomic_h5, check_kind, read_inputs, write_dataset
from ssw.plotting import pyplot, save_png
from ssw.tof.api import peaks
from ssw.validity import Validity

KIND = "tof_sweep"
FIELDS = ("soil_E", "soil_nu", "tof", "t_incident", "f_incident", "f_reflected")
UNITS = {"soil_E": "Pa", "soil_nu": "1", "tof": "s", "t_incident": "s", "f_incident": "N",
         "f_reflected": "N"}


@dataclass(frozen=True)
class Sweep:
    """Sweep points, flat arrays of one length. SI units.

    Parameters
    ----------
    soil_E : numpy.ndarray
        Soil Young's modulus (Pa).
    soil_nu : numpy.ndarray
        Soil Poisson's ratio.
    tof : numpy.ndarray
        TOF (s).
    t_incident : numpy.ndarray
        Incident peak time at the sensor (s).
    f_incident : numpy.ndarray
        Incident peak above the static force (N).
    f_reflected : numpy.ndarray
        Reflected peak above the static force (N).
    validity : Validity or None
        The checks of each point (:mod:`ssw.validity`), or None.
    """

    soil_E: np.ndarray  # Pa
    soil_nu: np.ndarray  # -
    tof: np.ndarray  # s
    t_incident: np.ndarray  # s, incident peak time at the sensor
    f_incident: np.ndarray  # N, incident peak above the static force
    f_reflected: np.ndarray  # N, reflected peak above the static force
    validity: Validity | None = None  # the checks of each point (ssw.validity)

    def sorted(self) -> Sweep:
        """Points ordered by (nu, E).

        Returns
        -------
        Sweep
            The sweep reordered.
        """
        order = np.lexsort((self.soil_E, self.soil_nu))
        return Sweep(*(getattr(self, k)[order] for k in FIELDS),
                     validity=None if self.validity is None else self.validity.take(order))

    def curve(self, soil_nu: float) -> tuple[np.ndarray, np.ndarray]:
        """``(E, TOF)`` at one Poisson's ratio, E increasing.

        Parameters
        ----------
        soil_nu : float
            Poisson's ratio of the soil (one of the sweep's).

        Returns
        -------
        E : numpy.ndarray
            Soil moduli (Pa), increasing.
        tof : numpy.ndarray
            TOFs (s).

        Raises
        ------
        ConfigError
            If the sweep has no point at ``soil_nu``.
        """
        sel = np.isclose(self.soil_nu, soil_nu, rtol=0, atol=1e-9)
        if not np.any(sel):
            raise ConfigError("soil_nu", soil_nu, f"one of the sweep's {np.unique(self.soil_nu)}")
        order = np.argsort(self.soil_E[sel])
        return self.soil_E[sel][order], self.tof[sel][order]


def grid_points(soil_E: Any, soil_nu: Any) -> tuple[np.ndarray, np.ndarray]:
    """The flat (nu-major) product of the axes.

    Parameters
    ----------
    soil_E : array_like
        Soil moduli (Pa).
    soil_nu : array_like
        Soil Poisson's ratios.

    Returns
    -------
    E : numpy.ndarray
        Moduli (Pa) of every point.
    nu : numpy.ndarray
        Poisson's ratios of every point.
    """
    nu, E = np.meshgrid(np.asarray(soil_nu, float), np.asarray(soil_E, float), indexing="ij")
    return E.ravel(), nu.ravel()


def chunk_slice(n_points: int, chunk: int, chunks: int) -> np.ndarray:
    """Indices of chunk ``chunk`` (0-based) of ``chunks``: interleaved.

    Parameters
    ----------
    n_points : int
        Number of points.
    chunk : int
        The chunk, 0-based.
    chunks : int
        Number of chunks, >= 1.

    Returns
    -------
    numpy.ndarray
        Point indices ``chunk, chunk + chunks, ...``.

    Raises
    ------
    ConfigError
        If ``chunks < 1`` or ``chunk`` is outside ``[0, chunks)``.
    """
    if not (chunks >= 1 and 0 <= chunk < chunks):
        raise ConfigError("chunk", f"{chunk} of {chunks}", "0 <= chunk < chunks, chunks >= 1")
    return np.arange(chunk, n_points, chunks)


def run_sweep(
    params: ChainParams,
    soil_E: np.ndarray,
    soil_nu: np.ndarray,
    wall: str = "hertz",
    *,
    comm: Any = None,
    on_progress: Any = None,
    strengths: Any = None,
    stresses: str = "bound",
    **wall_options: Any,
) -> Sweep:
    """TOF at the flat points ``(soil_E[i], soil_nu[i])``, split over ``comm``'s ranks.

    ``wall_options`` with a per-point sequence (``curve=[...]``, ``K=[...]``) are split
    along with the points; ``on_progress(k)`` is told when ``k`` of this rank's points
    finish. With ``strengths`` (:class:`ssw.validity.Strengths`) every point also gets its
    checks (:func:`ssw.validity.assess` of the same run; ``stresses`` its mode: ``bound``
    by default, the contact FEM's stresses only with ``fem``).

    Parameters
    ----------
    params : ChainParams
        The chain.
    soil_E : numpy.ndarray
        Soil moduli (Pa), one per point.
    soil_nu : numpy.ndarray
        Soil Poisson's ratios, one per point.
    wall : str
        The wall law's registry name.
    comm : Any
        An MPI communicator, or None for one process.
    on_progress : callable or None
        Called with the count of this rank's finished points.
    strengths : Strengths or None
        The sample's strengths for the validity checks, or None.
    stresses : str
        The checks' stress mode: ``bound`` or ``fem``.
    **wall_options : Any
        Options of the wall law.

    Returns
    -------
    Sweep
        TOFs (s), incident times (s) and peak forces (N) of every point.
    """
    from ssw.validity import assess, fem_options
    from ssw.walls import build_wall

    E, nu = (np.asarray(x, float).ravel() for x in (soil_E, soil_nu))
    size, rank = (1, 0) if comm is None else (comm.Get_size(), comm.Get_rank())
    mine = np.arange(rank, E.size, size)
    opts = {k: _part(v, mine, E.size) for k, v in wall_options.items()}
    cols = np.full((len(FIELDS) - 2, E.size), np.nan)
    checks = None
    if mine.size:
        pk, run = peaks(E[mine], nu[mine], params, wall, on_progress=on_progress, **opts)
        cols[:, mine] = [pk.tof, pk.t_incident, pk.f_incident, pk.f_reflected]
        if strengths is not None:
            w = build_wall(wall, params, E[mine], nu[mine], **opts)
            checks = assess(params, E[mine], nu[mine], run, pk, w, strengths=strengths,
                            stresses=stresses, **fem_options(wall, opts))
    if comm is not None and size > 1:
        parts = comm.allgather((mine, cols[:, mine], checks))
        for idx, vals, _ in parts:
            cols[:, idx] = vals
        if strengths is not None:
            got = [(idx, v) for idx, _, v in parts if v is not None]
            order = np.argsort(np.concatenate([idx for idx, _ in got]))
            checks = Validity.concat([v for _, v in got]).take(order)
    return Sweep(E, nu, *cols, validity=checks)


def _part(value: Any, idx: np.ndarray, n: int) -> Any:
    if isinstance(value, list | tuple | np.ndarray) and len(value) == n and n > 1:
        return [value[i] for i in idx] if isinstance(value, list | tuple) else value[idx]
    return value


def write_sweep(path: str | Path, sweep: Sweep, inputs: dict[str, Any]) -> None:
    """HDF5 (kind ``tof_sweep``) with one dataset per field.

    Parameters
    ----------
    path : str or pathlib.Path
        The HDF5 file, written atomically.
    sweep : Sweep
        The TOF sweep (SI).
    inputs : dict
        The provenance inputs to record.
    """
    with atomic_h5(path, kind=KIND, inputs=inputs) as f:
        for k in FIELDS:
            write_dataset(f, k, getattr(sweep, k), UNITS[k])
        if sweep.validity is not None:
            _write_validity(f, sweep.validity)


#: HDF5 group of a sweep's checks: one dataset per check, attribute ``meta_json``.
VALIDITY_GROUP = "validity"


def _write_validity(f: Any, v: Validity) -> None:
    """The checks of every point as datasets of :data:`VALIDITY_GROUP` (unit 1), what they
    rest on as its ``meta_json`` attribute."""
    from ssw.h5io import to_json

    g = f.create_group(VALIDITY_GROUP)
    for k, vals in v.values.items():
        write_dataset(g, k, vals, "1")
    g.attrs["meta_json"] = to_json(v.meta())


def _read_validity(f: Any) -> Validity | None:
    """The checks :func:`_write_validity` stored, or None (a sweep without them)."""
    import json

    if VALIDITY_GROUP not in f:
        return None
    g = f[VALIDITY_GROUP]
    meta = json.loads(g.attrs["meta_json"])
    return Validity({k: g[k][()] for k in g}, meta["assumed"], meta["bound"], meta["notes"],
                    meta["skipped"])


def read_sweep(path: str | Path) -> tuple[Sweep, dict[str, Any]]:
    """A sweep written by :func:`write_sweep` and its inputs.

    Parameters
    ----------
    path : str or pathlib.Path
        The HDF5 file.

    Returns
    -------
    sweep : Sweep
        The sweep (SI).
    inputs : dict
        Its recorded inputs.

    Raises
    ------
    SswError
        If there is no file at ``path``.
    """
    import h5py

    p = Path(path)
    if not p.is_file():
        raise SswError(f"no TOF sweep at {p}")
    with h5py.File(p, "r") as f:
        check_kind(f, KIND)
        return Sweep(*(f[k][()] for k in FIELDS), validity=_read_validity(f)), read_inputs(f)


def model_digest(params: ChainParams, wall: str, wall_options: dict[str, Any]) -> str:
    """Digest (``ssw.provenance.digest``) of the chain model a sweep is made of: every
    ChainParams field, the wall law and its plain options (a sweep records it; a command
    that reads a sweep in place of its own model compares).

    Parameters
    ----------
    params : ChainParams
        The chain.
    wall : str
        The wall law's registry name.
    wall_options : dict
        Options of the wall law.

    Returns
    -------
    str
        The digest.
    """
    from dataclasses import asdict

    from ssw.provenance import digest

    plain = {k: v for k, v in wall_options.items()
             if isinstance(v, str | int | float | bool | dict | list | tuple) or v is None}
    return digest({"params": asdict(params), "wall": wall, "wall_options": plain})


def sweep_model(inputs: dict[str, Any], path: str | Path) -> str:
    """The model digest a sweep file records (a merged sweep: its parts', which must
    agree); SswError when it records none.

    Parameters
    ----------
    inputs : dict
        The sweep file's inputs.
    path : str or pathlib.Path
        The sweep file (for the message).

    Returns
    -------
    str
        The model digest.

    Raises
    ------
    SswError
        If the sweep records no single model digest.
    """
    if "model_sha256" in inputs:
        return str(inputs["model_sha256"])
    parts = {p.get("model_sha256") for p in inputs.get("part_inputs", [])}
    if len(parts) == 1 and None not in parts:
        return str(parts.pop())
    raise SswError(f"{path}: the sweep records no single chain model (model_sha256): "
                   "remake it with this ssw")


def require_same_model(sweep_inputs: dict[str, Any], path: str | Path, params: ChainParams,
                       wall: str, wall_options: dict[str, Any]) -> None:
    """ProvenanceError unless a sweep was made of the command's own chain model (the same
    device, calibration, numerics and wall law), naming both sides.

    Parameters
    ----------
    sweep_inputs : dict
        The sweep file's inputs.
    path : str or pathlib.Path
        The sweep file (for the message).
    params : ChainParams
        The command's chain.
    wall : str
        The command's wall law.
    wall_options : dict
        The command's wall options.

    Raises
    ------
    ProvenanceError
        If the digests differ.
    """
    from ssw.provenance import require_match

    require_match("the chain model (device, calibration, numerics, wall law)",
                  (f"sweep {path}", sweep_model(sweep_inputs, path)),
                  ("this command's", model_digest(params, wall, wall_options)))


def merge_sweeps(sweeps: list[Sweep]) -> Sweep:
    """One sweep of all points, ordered by (nu, E); duplicates are an error.

    Parameters
    ----------
    sweeps : list of Sweep
        The chunks.

    Returns
    -------
    Sweep
        The merged sweep.

    Raises
    ------
    SswError
        If a point appears twice.
    """
    checks = ([s.validity for s in sweeps] if all(s.validity is not None for s in sweeps)
              else None)
    cat = Sweep(*(np.concatenate([getattr(s, k) for s in sweeps]) for k in FIELDS),
                validity=None if checks is None else Validity.concat(checks)).sorted()
    key = np.stack([cat.soil_nu, cat.soil_E])
    if cat.soil_E.size > 1 and np.any(np.all(np.diff(key, axis=1) == 0, axis=0)):
        raise SswError("merged sweep chunks overlap: a point appears twice")
    return cat


def write_csv(path: str | Path, sweep: Sweep) -> None:
    """CSV with a header naming the units; with the sweep's checks, one column per check
    (its value, dimensionless; ``_upper_bound`` after the name of an upper bound) and
    ``checks_failed`` (the failing checks' names, ``;``-joined) after the TOF columns.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file, written atomically.
    sweep : Sweep
        The TOF sweep (SI).
    """
    import io

    from ssw.h5io import write_csv_text

    head = "soil_E_Pa,soil_nu,tof_s,t_incident_s,f_incident_N,f_reflected_N"
    data = np.column_stack([getattr(sweep, k) for k in FIELDS])
    buf = io.StringIO()
    np.savetxt(buf, data, delimiter=",", header=head, comments="", fmt="%.10g")
    text = buf.getvalue()
    record = {k: getattr(sweep, k) for k in FIELDS}
    if sweep.validity is not None:
        text = _with_checks(text, sweep.validity)
        record["validity"] = {k: sweep.validity.values[k] for k in sweep.validity.values}
    write_csv_text(path, text, record)


def _with_checks(text: str, v: Validity) -> str:
    """CSV ``text`` (a header and one line per point) with the check columns appended."""
    cols = v.columns()
    names = [k for k in cols if k != "checks_failed"]
    head = [f"{k}_upper_bound" if v.bound.get(k) == "upper" else k for k in names]
    lines = text.rstrip("\n").split("\n")
    out = [lines[0] + "," + ",".join([*head, "checks_failed"])]
    for i, line in enumerate(lines[1:]):
        vals = [f"{cols[k][i]:.4g}" for k in names]
        out.append(line + "," + ",".join([*vals, str(cols["checks_failed"][i])]))
    return "\n".join(out) + "\n"


def plot_fig8(path: str | Path, sweep: Sweep, title: str = "") -> None:
    """TOF (ms) vs soil E (MPa), one line per nu (thesis Fig 8 style), PNG.

    Parameters
    ----------
    path : str or pathlib.Path
        The PNG file.
    sweep : Sweep
        The TOF sweep (SI).
    title : str
        The plot's title; empty: a default.
    """
    plt = pyplot()

    fig, ax = plt.subplots(figsize=(6, 4.2))
    for nu in np.unique(sweep.soil_nu):
        E, T = sweep.curve(float(nu))
        ax.plot(E / 1e6, T * 1e3, label=f"nu = {nu:g}")
    ax.set_xlabel("soil Young's modulus E (MPa)")
    ax.set_ylabel("TOF (ms)")
    ax.set_title(title or "TOF vs soil modulus (cf. thesis Fig 8)")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    save_png(fig, path, dpi=150)

"""What a chain run keeps of its scenes, step by step (:func:`ssw.chain.integrate.simulate`).

:class:`Record` holds the per-step rows of the active scenes in blocks of ``check_every``
steps and writes them, block by block, into the run's records ``(n_t, *shape, n)``, NaN
where a scene had stopped. :class:`Recorder` fills those rows from the compiled step
(:class:`ssw.chain.kernel.Stepper`): the sensor's reading of its two contacts
(``ChainParams.sensor_reads``), the wall's force, the sensor's sensitivities, every
contact force and the energy record (kinetic + elastic - the work potential of gravity and
the preload, a stateful wall's stored and dissipated energy, the contacts' damping work,
accumulated by the trapezoidal rule on the damping's power).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ssw.chain.params import Batch
from ssw.chain.statics import kinetic_energy, potential_energy

#: Bytes a record is first allocated for (virtual memory, touched only as the run goes; a
#: longer run doubles it). 128 MB holds the thesis sweep's 300 scenes whole and keeps the
#: reserved address space modest where a cluster limits virtual memory (ulimit -v, strict
#: overcommit); 1 GB measured the same CPU on that sweep (1.0 s).
RECORD_BYTES = 2**27


class Record:
    """Per-step rows of the active scenes, kept in blocks of ``check_every`` steps and
    written, block by block, into the records ``(n_t, *shape, n)``, NaN where a scene had
    stopped.

    The records are allocated for the run's longest possible length (up to
    :data:`RECORD_BYTES` each, then grown by doubling) and never initialised as a whole:
    only the rows a run reaches are written, so memory the run does not use is never
    touched. Writing each block straight into them, instead of keeping the blocks and
    assembling them at the end, halves the memory a run touches: on this project's
    virtual machines a process's first touch of memory costs about 2.7 ms per MB of CPU
    (a first 70 MB array 0.19 s, the next one 0.013 s), 0.2 s of a run of 1500 scenes.

    Parameters
    ----------
    shapes : dict
        Each record's name and the shape of one scene's row (``()``: a number).
    n : int
        Number of scenes.
    block : int
        Rows of a block (the steps between two stop checks).
    rows : int
        The run's longest possible number of rows.
    """

    def __init__(self, shapes: dict[str, tuple[int, ...]], n: int, block: int,
                 rows: int) -> None:
        self.n = n
        self.buf = {k: np.empty((block, *sh, n)) for k, sh in shapes.items()}
        row_bytes = 8 * n * max(int(np.prod(sh, dtype=int)) for sh in shapes.values())
        cap = max(block, min(rows, RECORD_BYTES // max(row_bytes, 1)))
        self.out = {k: np.empty((cap, *sh, n)) for k, sh in shapes.items()}
        self.filled = 0

    def _reserve(self, rows: int) -> None:
        """Room for ``rows`` rows (doubling the records, their filled rows copied)."""
        cap = next(iter(self.out.values())).shape[0]
        if rows <= cap:
            return
        cap = max(rows, 2 * cap)
        for k, x in self.out.items():
            y = np.empty((cap, *x.shape[1:]))
            y[: self.filled] = x[: self.filled]
            self.out[k] = y

    def flush(self, j0: int, rows: int, active: np.ndarray) -> dict[str, np.ndarray]:
        """Write rows ``0..rows-1`` of the buffers (steps ``j0..``) of the scenes ``active``
        into the records.

        Parameters
        ----------
        j0 : int
            The block's first step.
        rows : int
            Rows of the block filled.
        active : numpy.ndarray
            Indices of the scenes still running, (na,).

        Returns
        -------
        dict
            Those rows of the buffers (views, valid until the next block).
        """
        na = active.size
        self._reserve(j0 + rows)
        got = {k: b[:rows, ..., :na] for k, b in self.buf.items()}
        for k, x in got.items():
            dst = self.out[k][j0 : j0 + rows]
            if na == self.n:
                dst[...] = x
            else:
                dst[...] = np.nan
                dst[..., active] = x
        self.filled = j0 + rows
        return got

    def assemble(self, n_t: int) -> dict[str, np.ndarray]:
        """The records of the run's ``n_t`` rows.

        Parameters
        ----------
        n_t : int
            Rows of the run.

        Returns
        -------
        dict
            Each record, ``(n_t, *shape, n)``.
        """
        return {k: x[:n_t] for k, x in self.out.items()}


def read_sensor(reads: str, upper: np.ndarray, lower: np.ndarray, out: np.ndarray) -> None:
    """The sensor's reading of its two contacts' forces, written into ``out`` (the in-place
    form of :func:`ssw.chain.integrate.sensor_reading`).

    Parameters
    ----------
    reads : str
        ``ChainParams.sensor_reads``: ``upper``, ``lower`` or ``mean``.
    upper : numpy.ndarray
        N (or N per unit of a parameter), the contact above the sensor.
    lower : numpy.ndarray
        The contact below it, in the same unit and shape.
    out : numpy.ndarray
        Where the reading goes, the shape of ``upper``.
    """
    if reads == "upper":
        out[...] = upper
    elif reads == "lower":
        out[...] = lower
    else:
        np.add(upper, lower, out=out)
        out *= 0.5


class Recorder:
    """The rows a run records of its active scenes, step by step, into a :class:`Record`.

    Parameters
    ----------
    b : Batch
        The run's scenes.
    ch : ssw.chain.kernel.Stepper
        The compiled step, after its first force evaluation (its damping power is the
        energy record's start); the sensor's and the wall's rows are bound to it here.
    k : int or None
        Parameters of the forward sensitivities (None: none).
    rows : int
        The run's longest possible number of rows.
    block : int
        Rows of a block (the steps between two stop checks).
    record_forces : bool
        Also keep every contact force.
    record_energy : bool
        Also keep the energy record (``energy``, ``energy_wall``, ``dissipated``).
    dt : float
        The step (s), for the damping's work.
    """

    def __init__(self, b: Batch, ch: Any, k: int | None, rows: int, block: int,
                 record_forces: bool, record_energy: bool, dt: float) -> None:
        p, n = b.params, b.n
        self.b, self.k, self.reads, self.half = b, k, p.sensor_reads, 0.5 * dt
        self.forces, self.energy = record_forces, record_energy
        self.damped = record_energy and p.damping > 0.0
        shapes: dict[str, tuple[int, ...]] = {"sensor": (), "wall": ()}
        if k is not None:
            shapes.update(dsensor=(k,))
        if record_energy:
            shapes.update(energy=(), energy_wall=(), dissipated=())
            self.w_dash = np.zeros(n)  # the damping's work so far (J)
            self.p_dash = ch.power.copy() if ch.power is not None else np.zeros(n)
        if record_forces:
            shapes["forces"] = (p.n_beads,)
        self.rec = Record(shapes, n, block, rows)
        self.buf = self.rec.buf
        # the sensor's two contacts, step by step; read once per block (flush)
        self.pair = np.empty((block, 2, n))
        self.dpair = None if k is None else np.empty((block, 2, n, k))
        # the step's code fills the sensor's and the wall's rows and keeps the peaks: the
        # largest wall indentation and, per contact and active scene, bead-bead force
        # (reduced over the contacts when a scene stops)
        ch.start_record(p.sensor_index, self.buf["wall"], self.pair, self.dpair)

    def damping_work(self, ch: Any) -> None:
        """Add the step's damping work (trapezoidal rule on the damping's power) when the
        energy is recorded.

        Parameters
        ----------
        ch : ssw.chain.kernel.Stepper
            The step, after its force evaluation.
        """
        if self.damped:
            self.w_dash += self.half * (self.p_dash + ch.power)
            self.p_dash = ch.power.copy()

    def row(self, k: int, active: np.ndarray, ch: Any, wall: Any, state: Any,
            stateful: bool) -> None:
        """Row ``k`` of the block buffers (the active scenes' first columns).

        Parameters
        ----------
        k : int
            The row in the block.
        active : numpy.ndarray
            Indices of the scenes still running, (na,).
        ch : ssw.chain.kernel.Stepper
            The step, after its force evaluation.
        wall : Wall or StatefulWall
            The active scenes' wall (its potential, or a stateful wall's energy).
        state : Any
            A stateful wall's state (unused for a law of the indentation).
        stateful : bool
            Whether the wall has internal state.
        """
        na = active.size
        ch.record(k)
        if self.forces:
            self.buf["forces"][k, :, :na] = ch.f
        if self.energy:
            buf = self.buf
            sub = self.b.take(active)
            u, v = ch.z
            e = kinetic_energy(sub, v.T) + potential_energy(sub, None if stateful else wall,
                                                            u.T)
            stored = lost = 0.0
            if stateful:
                stored, lost = wall.energy(state)
            buf["energy_wall"][k, :na] = stored if stateful else np.nan
            buf["dissipated"][k, :na] = lost + self.w_dash
            buf["energy"][k, :na] = e + stored + lost + self.w_dash

    def flush(self, j0: int, rows: int, active: np.ndarray) -> dict[str, np.ndarray]:
        """The block's sensor readings, then :meth:`Record.flush`.

        Parameters
        ----------
        j0 : int
            The block's first step.
        rows : int
            Rows of the block filled.
        active : numpy.ndarray
            Indices of the scenes still running, (na,).

        Returns
        -------
        dict
            The block's rows (views, valid until the next block).
        """
        na, buf, dpair = active.size, self.buf, self.dpair
        read_sensor(self.reads, self.pair[:rows, 0, :na], self.pair[:rows, 1, :na],
                    buf["sensor"][:rows, :na])
        if dpair is not None:
            read_sensor(self.reads, dpair[:rows, 0, :na].transpose(0, 2, 1),
                        dpair[:rows, 1, :na].transpose(0, 2, 1),
                        buf["dsensor"][:rows, :, :na])
        return self.rec.flush(j0, rows, active)

    def keep(self, keep: np.ndarray) -> None:
        """Keep the scenes ``keep`` (bool over the active scenes) of the damping's work.

        Parameters
        ----------
        keep : numpy.ndarray
            Bool over the active scenes.
        """
        if self.energy:
            self.w_dash, self.p_dash = self.w_dash[keep], self.p_dash[keep]

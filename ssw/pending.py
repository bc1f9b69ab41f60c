"""Jobs of a Slurm run that never start: how long each may pend, and what the run does then.

A job Slurm keeps ``PENDING`` (a partition that never schedules it, a constraint or a feature
no node offers, a hold, a node that stays down, or a long queue) looks queued to every
status query. :class:`PendingWatch` counts how long each of a run's jobs has been pending and,
past the job's :class:`PendingLimit` (its resources ``ssw_pending_s`` and ``ssw_on_pending``,
:func:`pending_limit`; the SLURM profile's ``default-resources`` set them), reports it with
the reason ``squeue`` gives and stops the run or lets it wait. The lost-jobs watch of
:mod:`ssw.cluster` (:func:`ssw.cluster.watch_lost_jobs`) takes its looks.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ssw.errors import ConfigError

#: s, how long a job may pend before it is reported (job resource ``ssw_pending_s``: the
#: SLURM profile's ``default-resources``, a rule's ``set-resources``): an hour, long beside
#: the study's jobs (1-2 CPUs and 1-2 GB for minutes, which a cluster's backfill starts
#: soon) and short beside a run left alone overnight.
PENDING_LIMIT_S = 3600.0
#: What a run does with a job pending beyond its limit (job resource ``ssw_on_pending``):
#: ``stop`` the run (outputs of finished jobs are kept), or ``wait`` for the job, reporting
#: it again after each further limit. Either way the report names the job, how long it has
#: pended and the reason ``squeue`` gives.
PENDING_ACTIONS = ("stop", "wait")
#: The default of ``ssw_on_pending``.
ON_PENDING = "stop"


@dataclass(frozen=True)
class PendingLimit:
    """How long a job may pend, and what its run does then.

    Parameters
    ----------
    limit_s : float
        s, the time after which the job is reported.
    action : str
        ``stop`` (the run stops) or ``wait`` (the run waits, the job is reported again
        after each further ``limit_s``).
    """

    limit_s: float
    action: str


def pending_limit(resources: Mapping[str, Any]) -> PendingLimit:
    """A job's :class:`PendingLimit` from its resources (``ssw_pending_s``, s;
    ``ssw_on_pending``, ``stop`` or ``wait``), the defaults :data:`PENDING_LIMIT_S` and
    :data:`ON_PENDING` where they are not set.

    Parameters
    ----------
    resources : Mapping[str, Any]
        The job's resources (Snakemake's ``default-resources`` and ``set-resources``).

    Returns
    -------
    PendingLimit
        The job's limit and action.

    Raises
    ------
    ConfigError
        A limit that is not a positive number of seconds, or an action other than
        :data:`PENDING_ACTIONS`.
    """
    raw = resources.get("ssw_pending_s")
    try:
        limit = PENDING_LIMIT_S if raw is None else float(raw)
    except (TypeError, ValueError):
        limit = float("nan")
    if not 0 < limit < float("inf"):
        raise ConfigError("resources ssw_pending_s", raw,
                          f"a positive number of seconds a job may pend before it is "
                          f"reported (default {PENDING_LIMIT_S:g}; the SLURM profile's "
                          "default-resources, or --set-resources RULE:ssw_pending_s=...)")
    action = str(resources.get("ssw_on_pending") or ON_PENDING).strip().strip("'\"")
    if action not in PENDING_ACTIONS:
        raise ConfigError("resources ssw_on_pending", action,
                          f"{' or '.join(PENDING_ACTIONS)}: what the run does with a job "
                          "pending beyond ssw_pending_s (the SLURM profile's "
                          "default-resources, or --set-resources RULE:ssw_on_pending=...)")
    return PendingLimit(limit, action)


@dataclass
class PendingWatch:
    """Reports the jobs of a run that pend longer than their :class:`PendingLimit`, with the
    reason ``squeue`` gives (``PartitionConfig``, ``ReqNodeNotAvail``, ``JobHeldUser``,
    ``Priority``, ``Resources``, ...).

    A job counts as pending from the first look that sees it ``PENDING``; a look that sees
    it in any other state forgets it. Past its limit a job whose action is ``stop`` stops
    the run; one whose action is ``wait`` is reported, and again after each further limit.

    Other Parameters
    ----------------
    _since : dict of str to float
        Internal state: job id -> when it was first seen pending, s.
    _reported : dict of str to float
        Internal state: job id -> when it was last reported, s.
    """

    _since: dict[str, float] = field(default_factory=dict, repr=False)
    _reported: dict[str, float] = field(default_factory=dict, repr=False)

    def step(self, now: float, jobs: Mapping[str, tuple[str, str]],
             limits: Mapping[str, tuple[str, PendingLimit]]) -> tuple[str | None, str | None]:
        """Take one look.

        Parameters
        ----------
        now : float
            A monotonic clock, s.
        jobs : Mapping[str, tuple[str, str]]
            Slurm job id -> (state, reason) of the run's jobs
            (:func:`ssw.cluster.parse_job_lines`).
        limits : Mapping[str, tuple[str, PendingLimit]]
            Slurm job id -> (the job's name in the run, its limit); a job missing here is
            named by its id and gets the defaults.

        Returns
        -------
        tuple[str | None, str | None]
            The message that stops the run (jobs past their limit whose action is
            ``stop``), and the report of the jobs past their limit whose action is
            ``wait`` (due now); None where there is none.
        """
        pending = {j for j, (state, _) in jobs.items() if state == "PENDING"}
        for gone in set(self._since) - pending:
            self._since.pop(gone, None)
            self._reported.pop(gone, None)
        stop, wait = [], []
        for jid in sorted(pending):
            since = self._since.setdefault(jid, now)
            name, limit = limits.get(jid, (f"Slurm job {jid}",
                                           PendingLimit(PENDING_LIMIT_S, ON_PENDING)))
            last = self._reported.get(jid, since)
            if now - since < limit.limit_s or now - last < limit.limit_s:
                continue
            reason = jobs[jid][1] or "none given"
            what = (f"{name} (Slurm job {jid}) pending for {now - since:.0f} s, limit "
                    f"{limit.limit_s:g} s, squeue's reason: {reason}")
            if limit.action == "stop":
                stop.append(what)
            else:
                self._reported[jid] = now
                wait.append(what)
        stop_msg = None if not stop else (
            f"Cluster jobs pending beyond their limit: {len(stop)} job(s): "
            f"{'; '.join(stop)}. Slurm "
            "does not start them (the reason: squeue -j JOBID -o %r; scontrol show job "
            "JOBID for the whole story: a partition or a constraint no node offers, a hold, "
            "a node down, or a long queue). The run stops (resources ssw_on_pending=stop; "
            "ssw_on_pending=wait waits, ssw_pending_s sets the limit). Outputs of finished "
            "jobs are kept; run the same command again to redo the rest.")
        wait_msg = None if not wait else (
            f"{len(wait)} cluster job(s) pend beyond their limit: {'; '.join(wait)}. The "
            "run waits for them (resources ssw_on_pending=wait) and reports them again "
            "after each further limit.")
        return stop_msg, wait_msg

"""What a Slurm cluster can run, and how a run on it learns that its jobs ended.

Two ways a Snakemake run on Slurm waits forever without a word, both stopped here before or
while the run goes (the workflow's ``onstart`` handler, ``workflow/rules/common.smk``, through
:func:`ssw.workflow.prepare_slurm_run`):

* **A job no node can hold.** Slurm queues it forever (``Reason=PartitionConfig`` or
  ``Resources``). Every job about to be submitted is checked against the largest node
  (``sinfo``): :func:`check_jobs_fit` names the rule, the resource, the request and the
  node's size, and nothing is submitted.
* **A job whose end nobody sees.** snakemake-executor-plugin-slurm (2.8.0) asks Slurm for the
  states of a run's jobs with ``sacct`` (where the ``sacct`` binary exists) or ``squeue``
  (``--slurm-status-command``). On a cluster without accounting storage
  (``AccountingStorageType=accounting_storage/none``) every ``sacct`` query fails, and after
  its attempts the plugin drops the run's jobs from its list without reporting them:
  Snakemake then waits for them forever. With ``squeue``, a job the query does not list is
  taken as still queued, and slurmctld forgets a finished job ``MinJobAge`` seconds after
  its end. :func:`status_command` picks the command that works on the cluster (the run's
  settings are switched to it) or stops at once naming the flag; :class:`LostJobsWatch`
  stops a run whose jobs Slurm no longer shows as queued or running while Snakemake still
  waits for them.
* **A job that pends forever.** A partition that never schedules it, a constraint no node
  has, a hold: Slurm keeps it ``PENDING``, and every check above sees a queued job. The
  same watch reports a job pending longer than its limit, with the reason ``squeue`` gives,
  then stops the run or waits, reporting again after each further limit
  (:class:`ssw.pending.PendingWatch`; the job resources ``ssw_pending_s`` and
  ``ssw_on_pending``, :func:`ssw.pending.pending_limit`, which the SLURM profile sets).

The plugin's behaviour quoted here is that of its version pinned in ``constraints.txt``
(``snakemake_executor_plugin_slurm/__init__.py``, ``Executor.check_active_jobs``).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from ssw.errors import ConfigError, SswError
from ssw.pending import PendingLimit, PendingWatch

#: ``AccountingStorageType`` of a cluster without accounting storage (no ``sacct``).
NO_ACCOUNTING = "accounting_storage/none"

#: The executor plugin's longest pause between two status queries of a run, s (2.8.0:
#: ``max_sleep_time`` of ``check_active_jobs``; the pause starts at
#: ``--slurm-init-seconds-before-status-checks`` and grows by 10 s per query that sees no
#: job finish).
PLUGIN_MAX_STATUS_INTERVAL_S = 180.0

#: ssw's longest pause between two of the plugin's status queries of a run, s (environment
#: ``SSW_SLURM_STATUS_MAX_S``: :func:`slurm_timing`; applied by
#: :func:`ssw.workflow.cap_status_pause`). Left to grow to
#: :data:`PLUGIN_MAX_STATUS_INTERVAL_S`, the pause lets a job that ends just after a query
#: wait three minutes to be seen, longer than most of the study's jobs run; one query of
#: the run's jobs per 30 s stays light for a controller (Snakemake's own default for remote
#: executors is one per 10 s).
STATUS_PAUSE_MAX_S = 30.0

#: The plugin trades ``squeue`` for ``sacct`` (where the binary exists) when ``MinJobAge``
#: is shorter than this many times ``--slurm-init-seconds-before-status-checks`` (2.8.0).
PLUGIN_SQUEUE_AGE_FACTOR = 3

#: Job states (``squeue -o %T``, ``sacct -o State``) of a job that still waits for or holds
#: its resources; every other state (COMPLETED, FAILED, CANCELLED, TIMEOUT, OUT_OF_MEMORY,
#: NODE_FAIL, BOOT_FAIL, DEADLINE, PREEMPTED, REVOKED, SPECIAL_EXIT) is final. Slurm 22.05
#: ``squeue(1)``, JOB STATE CODES.
ACTIVE_STATES = frozenset({
    "PENDING", "RUNNING", "CONFIGURING", "COMPLETING", "SUSPENDED", "REQUEUED",
    "REQUEUE_FED", "REQUEUE_HOLD", "RESIZING", "SIGNALING", "STAGE_OUT", "STOPPED",
    "RESV_DEL_HOLD",
})

#: Seconds between two looks of :func:`watch_lost_jobs` at the run's jobs (environment
#: ``SSW_SLURM_WATCH_POLL_S``: :func:`slurm_timing`).
WATCH_POLL_S = 15.0
#: Seconds Slurm may list no job of a run at all (a submission in flight) before the run's
#: jobs count as lost (environment ``SSW_SLURM_VANISH_GRACE_S``: :func:`slurm_timing`).
VANISH_GRACE_S = 60.0


# --------------------------------------------------------------------- nodes and jobs
@dataclass(frozen=True)
class NodeLimits:
    """The largest node of a cluster, each field the maximum over its nodes.

    Parameters
    ----------
    cpus : int
        CPUs of the node with the most.
    mem_mb : int
        Memory of the node with the most, MB.
    """

    cpus: int
    mem_mb: int


def parse_sinfo(text: str) -> NodeLimits:
    """The largest node in ``sinfo -h -N -o "%c %m"`` output.

    Parameters
    ----------
    text : str
        One line per node: CPUs, memory in MB (``sinfo`` may append ``+`` to a range's
        lower end).

    Returns
    -------
    NodeLimits
        The maximum CPUs and the maximum memory over the nodes.

    Raises
    ------
    SswError
        No line names a node with CPUs and memory.
    """
    cpus, mem = 0, 0
    for line in text.splitlines():
        parts = line.split()
        if len(parts) < 2:
            continue
        try:
            c, m = int(parts[0].rstrip("+")), int(parts[1].rstrip("+"))
        except ValueError:
            continue
        cpus, mem = max(cpus, c), max(mem, m)
    if cpus <= 0 or mem <= 0:
        raise SswError(f"sinfo reported no node with CPUs and memory: {text.strip()!r}")
    return NodeLimits(cpus, mem)


def _run(cmd: list[str], what: str) -> str:
    """stdout of a Slurm command; SswError naming it when it is missing or fails."""
    if shutil.which(cmd[0]) is None:
        raise SswError(f"{cmd[0]} is not on PATH: is this a Slurm cluster's login node? "
                       f"({what})")
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=60, check=True)
    except (OSError, subprocess.SubprocessError) as exc:
        raise SswError(f"{' '.join(cmd)} failed ({what}): {exc}") from exc
    return out.stdout


def node_limits(partition: str | None = None) -> NodeLimits:
    """The largest node of the cluster, from ``sinfo``.

    Parameters
    ----------
    partition : str or None
        Only this partition's nodes (every node when None).

    Returns
    -------
    NodeLimits
        Its CPUs and memory.

    Raises
    ------
    SswError
        ``sinfo`` is missing or fails.
    """
    cmd = ["sinfo", "-h", "-N", "-o", "%c %m"]
    if partition:
        cmd += ["-p", partition]
    return parse_sinfo(_run(cmd, "the nodes' CPUs and memory"))


def job_cpus(threads: int, resources: Mapping[str, Any]) -> int:
    """CPUs a job's sbatch asks for (the Slurm executor's ``--cpus-per-task`` times
    ``--ntasks``).

    Parameters
    ----------
    threads : int
        The rule's threads (``--cpus-per-task`` unless resources ``cpus_per_task`` is set).
    resources : Mapping[str, Any]
        The job's resources (``cpus_per_task``, ``tasks``).

    Returns
    -------
    int
        CPUs per task times tasks.
    """
    per_task = resources.get("cpus_per_task") or threads or 1
    return int(per_task) * int(resources.get("tasks") or 1)


def oversized(jobs: Iterable[tuple[str, int, Mapping[str, Any]]], limits: NodeLimits
              ) -> list[str]:
    """The jobs that ask for more CPUs or memory than the largest node has.

    Parameters
    ----------
    jobs : Iterable[tuple[str, int, Mapping[str, Any]]]
        ``(rule, threads, resources)`` of each job; jobs over several nodes (resources
        ``nodes`` > 1) are not checked.
    limits : NodeLimits
        The largest node.

    Returns
    -------
    list[str]
        One message per request that no node can hold.
    """
    out = []
    for rule, threads, res in jobs:
        if int(res.get("nodes") or 1) > 1:
            continue
        cpus = job_cpus(threads, res)
        if cpus > limits.cpus:
            out.append(f"rule {rule} asks for {cpus} CPUs (threads/cpus_per_task x tasks); "
                       f"the largest node has {limits.cpus}")
        mem = res.get("mem_mb")
        if mem is not None and int(mem) > limits.mem_mb:
            out.append(f"rule {rule} asks for mem_mb={int(mem)}; the largest node has "
                       f"{limits.mem_mb} MB")
    return out


def check_jobs_fit(jobs: Iterable[tuple[str, int, Mapping[str, Any]]],
                   limits: NodeLimits | None = None) -> None:
    """Stop a run that holds a job no node can run (:func:`oversized`).

    Parameters
    ----------
    jobs : Iterable[tuple[str, int, Mapping[str, Any]]]
        ``(rule, threads, resources)`` of each job to be submitted.
    limits : NodeLimits or None
        The largest node (None: :func:`node_limits`).

    Raises
    ------
    ConfigError
        Listing every request that no node can hold.
    """
    limits = limits or node_limits()
    bad = sorted(set(oversized(jobs, limits)))
    if bad:
        raise ConfigError("resources", "; ".join(bad),
                          "requests a node of the cluster can hold (lower them with "
                          "--set-resources RULE:mem_mb=... or the profile's set-resources; "
                          "no job was submitted)")


# --------------------------------------------------------------------- job states
@dataclass(frozen=True)
class SlurmConfig:
    """What the controller says about how long it keeps jobs (``scontrol show config``).

    Parameters
    ----------
    accounting_storage : str
        ``AccountingStorageType`` (:data:`NO_ACCOUNTING`: no ``sacct`` history).
    min_job_age_s : int or None
        ``MinJobAge``, s: how long slurmctld (and so ``squeue``) keeps a finished job;
        None when the controller does not say.
    """

    accounting_storage: str
    min_job_age_s: int | None

    @property
    def keeps_accounting(self) -> bool:
        """Whether ``sacct`` can answer (accounting storage other than none)."""
        return self.accounting_storage != NO_ACCOUNTING


def _seconds(value: str) -> int | None:
    """Seconds of a ``scontrol`` duration such as ``300 sec``, ``5 min`` or ``1h``."""
    m = re.match(r"^\s*(\d+)\s*([a-zA-Z]*)", value)
    if not m:
        return None
    unit = m.group(2).lower()
    scale = {"h": 3600, "hour": 3600, "hours": 3600, "min": 60, "mins": 60,
             "minute": 60, "minutes": 60}.get(unit, 1)
    return int(m.group(1)) * scale


def parse_scontrol_config(text: str) -> SlurmConfig:
    """The accounting storage and ``MinJobAge`` in ``scontrol show config`` output.

    Parameters
    ----------
    text : str
        ``Key = value`` lines.

    Returns
    -------
    SlurmConfig
        The two settings (accounting ``none`` when the output does not name it: without
        the key Slurm keeps no accounting).
    """
    values = {}
    for line in text.splitlines():
        key, sep, value = line.partition("=")
        if sep:
            values[key.strip()] = value.strip()
    age = values.get("MinJobAge")
    return SlurmConfig(values.get("AccountingStorageType", NO_ACCOUNTING),
                       None if age is None else _seconds(age))


def slurm_config() -> SlurmConfig:
    """This cluster's :class:`SlurmConfig`, from ``scontrol show config``.

    Returns
    -------
    SlurmConfig
        Its accounting storage and ``MinJobAge``.

    Raises
    ------
    SswError
        ``scontrol`` is missing or fails.
    """
    return parse_scontrol_config(_run(["scontrol", "show", "config"],
                                      "the controller's accounting and MinJobAge"))


def effective_status_command(requested: str, min_job_age_s: int | None, init_s: int,
                             sacct_on_path: bool) -> str:
    """The command the executor plugin queries job states with, given its setting.

    Parameters
    ----------
    requested : str
        ``--slurm-status-command`` (``sacct`` or ``squeue``; the plugin's default is
        ``sacct`` wherever the binary exists).
    min_job_age_s : int or None
        The cluster's ``MinJobAge``, s (None: unknown).
    init_s : int
        ``--slurm-init-seconds-before-status-checks``, s.
    sacct_on_path : bool
        Whether the ``sacct`` binary exists.

    Returns
    -------
    str
        ``sacct`` or ``squeue``: the plugin (2.8.0) trades ``squeue`` for ``sacct`` when the
        binary exists and ``MinJobAge`` is unknown or shorter than
        :data:`PLUGIN_SQUEUE_AGE_FACTOR` x ``init_s``, and ``sacct`` for ``squeue`` when
        the binary is missing.
    """
    cmd = requested
    if cmd == "squeue" and sacct_on_path and (
            min_job_age_s is None or min_job_age_s < PLUGIN_SQUEUE_AGE_FACTOR * init_s):
        cmd = "sacct"
    if cmd == "sacct" and not sacct_on_path:
        cmd = "squeue"
    return cmd


def status_command(cluster: SlurmConfig, requested: str, init_s: int,
                   sacct_on_path: bool) -> str:
    """The ``--slurm-status-command`` that lets a run see its jobs end on this cluster.

    Parameters
    ----------
    cluster : SlurmConfig
        The controller's accounting storage and ``MinJobAge``.
    requested : str
        The run's ``--slurm-status-command`` (``sacct`` or ``squeue``).
    init_s : int
        The run's ``--slurm-init-seconds-before-status-checks``, s.
    sacct_on_path : bool
        Whether the ``sacct`` binary exists.

    Returns
    -------
    str
        ``requested`` where the cluster keeps accounting (``sacct`` works there, and
        ``squeue`` is the user's choice); ``squeue`` on a cluster without accounting,
        where every ``sacct`` query fails.

    Raises
    ------
    ConfigError
        On a cluster without accounting whose ``MinJobAge`` is unknown or shorter than
        :data:`PLUGIN_SQUEUE_AGE_FACTOR` x ``init_s``: the plugin would query with
        ``sacct`` whatever the setting (:func:`effective_status_command`), so no job is
        submitted and the message names the flag that helps.
    """
    if cluster.keeps_accounting:
        return requested
    cmd = "squeue"
    if effective_status_command(cmd, cluster.min_job_age_s, init_s, sacct_on_path) != cmd:
        age = cluster.min_job_age_s
        limit = "" if age is None else f" = {age // PLUGIN_SQUEUE_AGE_FACTOR} s"
        raise ConfigError(
            "--slurm-init-seconds-before-status-checks", init_s,
            f"at most MinJobAge/{PLUGIN_SQUEUE_AGE_FACTOR}{limit} on this cluster "
            f"(MinJobAge = {age}): it keeps no accounting (AccountingStorageType = "
            f"{cluster.accounting_storage}), so job states can only come from squeue, and "
            "the executor plugin queries sacct instead when MinJobAge is shorter than "
            f"{PLUGIN_SQUEUE_AGE_FACTOR} x this delay; every sacct query fails there and "
            "the run would wait forever (no job was submitted)")
    return cmd


def short_job_age(cluster: SlurmConfig, status: str,
                  pause_s: float = PLUGIN_MAX_STATUS_INTERVAL_S) -> str | None:
    """A warning when ``squeue`` may forget a finished job before a status query sees it.

    Parameters
    ----------
    cluster : SlurmConfig
        The controller's ``MinJobAge``.
    status : str
        The status command the run uses.
    pause_s : float
        s, the run's longest pause between two status queries (:func:`slurm_timing`;
        default the plugin's own, :data:`PLUGIN_MAX_STATUS_INTERVAL_S`).

    Returns
    -------
    str or None
        The warning when the run queries ``squeue`` and ``MinJobAge`` is shorter than that
        pause, else None.
    """
    age = cluster.min_job_age_s
    if status != "squeue" or age is None or age >= pause_s:
        return None
    return (f"MinJobAge = {age} s is shorter than the longest pause between the run's "
            f"status queries ({pause_s:.0f} s): squeue may "
            "forget a finished job before a query sees it; such a run stops with a message "
            "(ssw.cluster.LostJobsWatch). Ask for MinJobAge >= 300 s.")


def parse_job_lines(text: str) -> dict[str, tuple[str, str]]:
    """Job id -> (state, reason) in ``ID|STATE[|REASON]`` lines (:func:`squeue_command`;
    ``squeue -o '%i|%T'``, ``sacct --parsable2 -o JobIdRaw,State``).

    Parameters
    ----------
    text : str
        The command's output.

    Returns
    -------
    dict[str, tuple[str, str]]
        The state's first word (``sacct`` writes ``CANCELLED by 0``), upper case, and the
        reason as given (``""`` when the line has none).
    """
    out = {}
    for line in text.splitlines():
        jid, _, rest = line.partition("|")
        state, _, reason = rest.partition("|")
        if jid.strip() and state.strip():
            out[jid.strip()] = (state.split()[0].upper(), reason.strip())
    return out


def parse_job_states(text: str) -> dict[str, str]:
    """Job id -> state in ``ID|STATE[|REASON]`` lines (:func:`parse_job_lines`).

    Parameters
    ----------
    text : str
        The command's output.

    Returns
    -------
    dict[str, str]
        The state's first word, upper case.
    """
    return {jid: state for jid, (state, _) in parse_job_lines(text).items()}


def squeue_command(run_id: str) -> list[str]:
    """The ``squeue`` query of a run's jobs: id, state and Slurm's reason for the state.

    Parameters
    ----------
    run_id : str
        The run's Slurm job name (the executor plugin names every job of a run by its run
        ID).

    Returns
    -------
    list[str]
        The command and its arguments (``ID|STATE|REASON`` lines, every state).
    """
    return ["squeue", "--format=%i|%T|%r", "--states=all", "--noheader", "--name", run_id]


@dataclass
class LostJobsWatch:
    """Decides when a run's cluster jobs are lost: Snakemake waits for jobs, and Slurm
    shows none of the run's jobs queued or running.

    Two cases, each with its own patience:

    * **vanished**: Slurm lists no job of the run at all for ``vanish_s`` (slurmctld forgot
      them ``MinJobAge`` after their end, or lost its state); an executor plugin that
      queries ``squeue`` takes them as still queued forever;
    * **unseen**: every job of the run Slurm lists has ended, for ``stall_s``: longer than
      the plugin's longest pause between queries, so its queries no longer report them (it
      drops the jobs of a status query that failed on every attempt).

    Parameters
    ----------
    vanish_s : float
        Patience of the vanished case, s.
    stall_s : float
        Patience of the unseen case, s.

    Other Parameters
    ----------------
    _absent_since : float or None
        Internal state: when Slurm first listed no job of the run, s (None: not now).
    _ended_since : float or None
        Internal state: when every listed job had first ended, s (None: not now).
    """

    vanish_s: float
    stall_s: float
    _absent_since: float | None = field(default=None, repr=False)
    _ended_since: float | None = field(default=None, repr=False)

    def step(self, now: float, waiting: Sequence[str], states: Mapping[str, str] | None
             ) -> str | None:
        """Take one look; the message when the run's jobs count as lost.

        Parameters
        ----------
        now : float
            A monotonic clock, s.
        waiting : Sequence[str]
            The cluster jobs Snakemake waits for (their names).
        states : Mapping[str, str] or None
            Job id -> state of the run's jobs (None: the query failed; the look counts for
            nothing).

        Returns
        -------
        str or None
            Why the run cannot end, naming the jobs; None while it can.
        """
        if not waiting:
            self._absent_since = self._ended_since = None
            return None
        if states is None:
            return None
        if any(s in ACTIVE_STATES for s in states.values()):
            self._absent_since = self._ended_since = None
            return None
        names = ", ".join(waiting[:10]) + (f" and {len(waiting) - 10} more"
                                            if len(waiting) > 10 else "")
        if not states:
            self._ended_since = None
            self._absent_since = now if self._absent_since is None else self._absent_since
            if now - self._absent_since >= self.vanish_s:
                return (f"Slurm lists no job of this run any more (for "
                        f"{now - self._absent_since:.0f} s) while Snakemake waits for "
                        f"{len(waiting)} cluster job(s): {names}. Their ends cannot be seen: "
                        "slurmctld forgets a finished job MinJobAge after it ends (scontrol "
                        "show config), or lost its jobs in a restart. Outputs of finished "
                        "jobs are kept; run the same command again to redo the rest.")
            return None
        self._absent_since = None
        self._ended_since = now if self._ended_since is None else self._ended_since
        if now - self._ended_since >= self.stall_s:
            ended = ", ".join(f"{j} {s}" for j, s in sorted(states.items())[:10])
            return (f"every Slurm job of this run has ended ({ended}) for "
                    f"{now - self._ended_since:.0f} s, but the executor plugin's status "
                    f"queries no longer report them, while Snakemake waits for "
                    f"{len(waiting)} cluster job(s): {names}. Outputs of finished jobs "
                    "are kept; run the same command again to redo the rest.")
        return None


def _env_seconds(environ: Mapping[str, str], name: str, default: float) -> float:
    """A positive, finite number of seconds from the environment variable ``name``, or
    ``default`` when it is unset or empty; a ConfigError naming the variable otherwise."""
    raw = environ.get(name, "").strip()
    try:
        value = float(raw) if raw else default
    except ValueError:
        value = float("nan")
    if not value > 0 or value == float("inf"):
        raise ConfigError(name, raw, f"a positive number of seconds (default {default:g}); "
                          f"unset {name} for the default")
    return value


class SlurmTiming(NamedTuple):
    """A Slurm run's timing, s (:func:`slurm_timing`).

    Parameters
    ----------
    vanish_s : float
        How long Slurm may list no job of the run before its jobs count as lost, s.
    poll_s : float
        The lost-jobs watch's pause between two looks, s.
    status_pause_s : float
        The longest pause between two of the executor plugin's status queries, s.
    """

    #: How long Slurm may list no job of the run before its jobs count as lost.
    vanish_s: float
    #: The lost-jobs watch's pause between two looks.
    poll_s: float
    #: The longest pause between two of the executor plugin's status queries.
    status_pause_s: float


def slurm_timing(environ: Mapping[str, str]) -> SlurmTiming:
    """A Slurm run's timing: the defaults or the environment's values.

    ``SSW_SLURM_VANISH_GRACE_S`` (default :data:`VANISH_GRACE_S`) is how long Slurm may list
    no job of a run before its jobs count as lost: longer on a controller whose submissions
    take minutes to appear in ``squeue``, shorter where a lost run should stop sooner.
    ``SSW_SLURM_WATCH_POLL_S`` (default :data:`WATCH_POLL_S`) is the lost-jobs watch's pause
    between two looks. ``SSW_SLURM_STATUS_MAX_S`` (default :data:`STATUS_PAUSE_MAX_S`, never
    more than the plugin's own :data:`PLUGIN_MAX_STATUS_INTERVAL_S`) is the longest pause
    between two status queries: a job is seen to end about that long after it ends at most;
    shorter on a small cluster of short jobs (the project's tests use 2 s), longer where the
    controller asks users to query it seldom.

    Parameters
    ----------
    environ : Mapping[str, str]
        The environment of the Snakemake run (``os.environ``).

    Returns
    -------
    SlurmTiming
        The grace, the watch's poll and the longest status pause, s.

    Raises
    ------
    ConfigError
        A value that is not a positive number of seconds, or a poll longer than the grace.
    """
    vanish_s = _env_seconds(environ, "SSW_SLURM_VANISH_GRACE_S", VANISH_GRACE_S)
    poll_s = _env_seconds(environ, "SSW_SLURM_WATCH_POLL_S", WATCH_POLL_S)
    if poll_s > vanish_s:
        raise ConfigError("SSW_SLURM_WATCH_POLL_S", f"{poll_s:g}",
                          f"at most SSW_SLURM_VANISH_GRACE_S ({vanish_s:g} seconds): the "
                          "watch must look at least once within the grace")
    pause_s = _env_seconds(environ, "SSW_SLURM_STATUS_MAX_S", STATUS_PAUSE_MAX_S)
    return SlurmTiming(vanish_s, poll_s, min(pause_s, PLUGIN_MAX_STATUS_INTERVAL_S))


def watch_lost_jobs(query: Callable[[], Mapping[str, tuple[str, str]] | None],
                    waiting: Callable[[], Sequence[str]],
                    on_lost: Callable[[str], None], stall_s: float,
                    vanish_s: float = VANISH_GRACE_S, poll_s: float = WATCH_POLL_S,
                    limits: Callable[[], Mapping[str, tuple[str, PendingLimit]]] | None = None,
                    on_note: Callable[[str], None] | None = None) -> Any:
    """Start a daemon thread that calls ``on_lost`` once when a run's jobs are lost
    (:class:`LostJobsWatch`) or pend beyond their limit with the action ``stop``
    (:class:`ssw.pending.PendingWatch`), and ``on_note`` with each report of jobs pending
    beyond their limit with the action ``wait``.

    Parameters
    ----------
    query : Callable[[], Mapping[str, tuple[str, str]] | None]
        Job id -> (state, reason) of the run's jobs as the controller lists them
        (:func:`squeue_command`, :func:`query_jobs`; None when the query fails).
    waiting : Callable[[], Sequence[str]]
        The cluster jobs Snakemake waits for.
    on_lost : Callable[[str], None]
        Called with the message that stops the run (``Lost cluster jobs: ...``, ``Cluster
        jobs pending beyond their limit: ...``); the thread ends after it.
    stall_s : float
        ``LostJobsWatch.stall_s``, s.
    vanish_s : float
        ``LostJobsWatch.vanish_s``, s.
    poll_s : float
        Seconds between two looks.
    limits : Callable[[], Mapping[str, tuple[str, PendingLimit]]] or None
        Slurm job id -> (job name, :class:`ssw.pending.PendingLimit`) of the run's jobs
        (None: every job gets the defaults). A ConfigError it raises (a job's limit that
        is not allowed) is passed to ``on_lost``.
    on_note : Callable[[str], None] or None
        Called with each report of the ``wait`` action (None: not reported).

    Returns
    -------
    threading.Thread
        The started thread.
    """
    import threading
    import time

    watch = LostJobsWatch(vanish_s, stall_s)
    pending = PendingWatch()

    def loop() -> None:
        while True:
            time.sleep(poll_s)
            try:
                names = list(waiting())
            except RuntimeError:  # Snakemake changed its set of running jobs meanwhile
                continue
            jobs = query() if names else {}
            now = time.monotonic()
            if jobs:
                try:
                    stop, note = pending.step(now, jobs, limits() if limits else {})
                except ConfigError as exc:
                    on_lost(str(exc))
                    return
                if stop is not None:
                    on_lost(stop)
                    return
                if note is not None and on_note is not None:
                    on_note(note)
            states = None if jobs is None else {j: st for j, (st, _) in jobs.items()}
            msg = watch.step(now, names, states)
            if msg is not None:
                on_lost(f"Lost cluster jobs: {msg}")
                return

    thread = threading.Thread(target=loop, name="ssw-lost-jobs-watch", daemon=True)
    thread.start()
    return thread


def query_jobs(command: Sequence[str]) -> dict[str, tuple[str, str]] | None:
    """Job id -> (state, reason) from a status command (``ID|STATE[|REASON]`` lines, such as
    :func:`squeue_command`'s); None when it fails.

    Parameters
    ----------
    command : Sequence[str]
        The command and its arguments (run without a shell).

    Returns
    -------
    dict[str, tuple[str, str]] or None
        :func:`parse_job_lines` of its output.
    """
    try:
        out = subprocess.run(list(command), capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return None
    return parse_job_lines(out.stdout) if out.returncode == 0 else None

"""The Snakemake run around the jobs: its end (the scheduler's timers), the quoting of the
interpreter in the jobs it spawns, and a run on Slurm (its status queries, the nodes' fit,
the watch over lost and pending jobs: :mod:`ssw.cluster`).

Called from the Snakefile's ``onstart``, ``onsuccess`` and ``onerror``; nothing here is
imported before Snakemake has started (its own modules are imported where used).
"""

from __future__ import annotations

from typing import Any


def end_of_run() -> int:
    """Cancel the job scheduler's pending timers once a run is over (the workflow's
    ``onsuccess`` and ``onerror``).

    Snakemake's scheduler arms a ``threading.Timer`` at every scheduling round (its job-rate
    limit, ``--max-jobs-per-timespan``, 1 s by default) to look again for jobs to start.
    The timers are not daemon threads: the process waits for the last one before it exits,
    a second after its last job (measured: 1.3 s from "Complete log" to the exit of a
    two-job workflow, 0.3-0.4 s without the timers). After the last job no timer has anything
    left to do.

    Returns
    -------
    int
        How many timers were cancelled.
    """
    import threading

    timers = [t for t in threading.enumerate() if isinstance(t, threading.Timer)]
    for t in timers:
        t.cancel()
    return len(timers)


def submits_to_slurm(workflow: Any) -> bool:
    """Whether a Snakemake run submits its jobs to Slurm (the ``slurm`` executor).

    Parameters
    ----------
    workflow : snakemake.workflow.Workflow
        The running workflow.

    Returns
    -------
    bool
        True when its executor plugin is ``slurm``.
    """
    plugin = getattr(workflow, "executor_plugin", None)
    return plugin is not None and getattr(plugin, "name", "") == "slurm"


def check_cluster_fit(workflow: Any) -> None:
    """ConfigError naming every job of the run that asks for more than the largest node
    has (:func:`ssw.cluster.check_jobs_fit`), before anything is submitted.

    Parameters
    ----------
    workflow : snakemake.workflow.Workflow
        The running workflow (its DAG's jobs to run, local jobs left out).

    Raises
    ------
    ssw.errors.ConfigError
        When a job asks for more cores, memory or time than any node has.
    """
    from ssw.cluster import check_jobs_fit

    jobs = [(j.rule.name, int(j.threads), dict(j.resources.items()))
            for j in workflow.dag.needrun_jobs() if not j.is_local]
    check_jobs_fit(jobs)


def _job_name(job: Any) -> str:
    """A Snakemake job as ``rule[wildcard=value,...]`` (a group job: its group)."""
    rule = getattr(job, "rule", None)
    if rule is None:
        return str(job)
    wildcards = getattr(job, "wildcards_dict", None) or {}
    return rule.name + (f"[{','.join(f'{k}={v}' for k, v in wildcards.items())}]"
                        if wildcards else "")


def cap_status_pause(executor: Any, pause_s: float) -> None:
    """Hold the executor plugin's pause between two status queries at ``pause_s`` at most.

    The Slurm plugin (2.8.0, ``Executor.check_active_jobs``) sets the pause before the next
    query at the end of each query: back to ``--slurm-init-seconds-before-status-checks``
    when a job ended, else 10 s longer, up to 180 s. Each query is wrapped here, and the
    pause it leaves is clipped to ``pause_s`` (:func:`ssw.cluster.slurm_timing`), so
    that a job is seen to end at most ``pause_s`` after it ends.

    Parameters
    ----------
    executor : snakemake_interface_executor_plugins.executors.remote.RemoteExecutor
        The run's executor (``next_seconds_between_status_checks``, ``check_active_jobs``
        an async generator of the jobs still active).
    pause_s : float
        s, the longest pause.
    """
    query = executor.check_active_jobs

    async def capped(active_jobs: list[Any]) -> Any:
        async for job in query(active_jobs):
            yield job
        if executor.next_seconds_between_status_checks > pause_s:
            executor.next_seconds_between_status_checks = pause_s

    executor.check_active_jobs = capped


def cancel_in_flight(executor: Any) -> None:
    """Make an interrupted run cancel the jobs a status query holds too.

    The remote executor (snakemake-interface-executor-plugins 9.x,
    ``RemoteExecutor._wait_for_jobs``) takes every job out of ``active_jobs`` for the time of
    a status query (a ``squeue`` or ``sacct`` call: up to seconds) and puts back those still
    active after it; ``cancel`` (Ctrl-C, SIGTERM) cancels what ``active_jobs`` holds, so an
    interruption during a query left every job of the run queued or running on the cluster.
    Each query is wrapped here to keep the jobs it holds until they are back in the list
    (those it reports ended leave with its end), and ``cancel_jobs`` cancels them with the
    listed ones, each once.

    Parameters
    ----------
    executor : snakemake_interface_executor_plugins.executors.remote.RemoteExecutor
        The run's executor (``check_active_jobs`` an async generator of the jobs still
        active, ``cancel_jobs`` the plugin's scancel of a list of jobs).
    """
    query, cancel = executor.check_active_jobs, executor.cancel_jobs
    held: list[Any] = []

    async def holding(active_jobs: list[Any]) -> Any:
        held[:] = list(active_jobs)
        still: list[Any] = []
        async for job in query(active_jobs):
            still.append(job)
            yield job
        held[:] = still  # back in active_jobs next, under the executor's lock

    def cancel_all(active_jobs: list[Any]) -> None:
        jobs = {id(j): j for j in [*active_jobs, *list(held)]}
        cancel(list(jobs.values()))

    executor.check_active_jobs = holding
    executor.cancel_jobs = cancel_all


#: The executors whose spawned jobs' command lines name the interpreter unquoted
#: (snakemake-interface-executor-plugins 9.4, ``format_job_exec``): (module, class).
_SPAWNING_EXECUTORS = (
    ("snakemake_interface_executor_plugins.executors.remote", "RemoteExecutor"),
    ("snakemake_executor_plugin_slurm_jobstep", "Executor"),
    ("snakemake.executors.local", "Executor"),
)


def quote_job_python() -> list[str]:
    """Quote the interpreter in the command lines of the jobs Snakemake spawns.

    An executor that runs a job as ``python -m snakemake ...`` (the Slurm submission's, the
    Slurm job step's inside each job, the local one's for a ``run:`` rule) puts
    ``sys.executable`` into the command line unquoted, its other arguments quoted: a venv
    under a folder whose name holds a space (``~/My Projects/ssw/.venv``) makes every such
    job fail with ``/home/me/My: not found`` (snakemake issue 3211). Each executor class of
    ``_SPAWNING_EXECUTORS`` already imported (Snakemake loads the run's executor
    plugin before it reads the Snakefile; none is imported here) gets a
    ``get_python_executable`` whose answer is shell-quoted (unchanged for a path without
    special characters). Idempotent.

    Returns
    -------
    list of str
        The classes changed by this call, ``module.Class``.
    """
    import shlex
    import sys

    changed = []
    for module, name in _SPAWNING_EXECUTORS:
        cls = getattr(sys.modules.get(module), name, None)
        plain = getattr(cls, "get_python_executable", None)
        if cls is None or plain is None or getattr(plain, "ssw_quoted", False):
            continue

        def quoted(self: Any, _plain: Any = plain) -> str:
            return shlex.quote(str(_plain(self)))

        quoted.ssw_quoted = True  # type: ignore[attr-defined]
        cls.get_python_executable = quoted
        changed.append(f"{module}.{name}")
    return changed


def prepare_slurm_run(workflow: Any) -> list[str]:
    """Make a Snakemake run on Slurm see its jobs end, before anything is submitted.

    On a cluster without accounting storage the run's status command becomes ``squeue``
    (:func:`ssw.cluster.status_command`; or a ConfigError naming the flag), every job must
    fit a node (:func:`check_cluster_fit`), the pause between two status queries stops
    growing at the run's limit (:func:`ssw.cluster.slurm_timing`, :func:`cap_status_pause`),
    an interruption cancels every job submitted (:func:`cancel_in_flight`), and a watch
    stops the run with a message when its jobs are lost, and when a job pends beyond its
    limit stops the run or reports the job, as its resources ``ssw_pending_s`` and
    ``ssw_on_pending`` say (:func:`ssw.cluster.watch_lost_jobs`, with a ``squeue``
    query of the run's jobs by the run's job name, as the executor plugin's own, and
    Slurm's reason for each state).

    Parameters
    ----------
    workflow : snakemake.workflow.Workflow
        The run (the ``workflow`` of a Snakefile's ``onstart``; its executor is ``slurm``).

    Returns
    -------
    list[str]
        What changed or may go wrong, one line each, for the run's log.

    Raises
    ------
    ConfigError
        A job no node can hold, or a cluster on which the plugin cannot see jobs end.
    """
    import os
    import shutil

    from ssw import cluster
    from ssw.pending import pending_limit

    notes = []
    settings = workflow.executor_settings
    info = cluster.slurm_config()
    sacct = shutil.which("sacct") is not None
    init_s = int(settings.init_seconds_before_status_checks)
    wanted = cluster.status_command(info, settings.status_command, init_s, sacct)
    if wanted != settings.status_command:
        notes.append(f"this Slurm keeps no job accounting (AccountingStorageType = "
                     f"{info.accounting_storage}): job states come from {wanted}, as with "
                     f"--slurm-status-command {wanted}")
        settings.status_command = wanted
    used = cluster.effective_status_command(wanted, info.min_job_age_s, init_s, sacct)
    timing = cluster.slurm_timing(os.environ)
    pause_s = timing.status_pause_s
    warning = cluster.short_job_age(info, used, pause_s)
    if warning:
        notes.append(warning)
    check_cluster_fit(workflow)

    scheduler = workflow.scheduler
    executor = getattr(scheduler, "_executor", None)
    if executor is not None:
        cap_status_pause(executor, pause_s)
        cancel_in_flight(executor)
    run_id = getattr(executor, "run_uuid", None)
    if run_id is None:
        notes.append("the lost-jobs watch is off: the Slurm executor has no run ID")
        return notes
    # The controller's view of the run's jobs (squeue, by the run's job name, as the plugin's
    # own query, with Slurm's reason for each state): with squeue as the status command a
    # job it no longer lists is lost to the run after the short grace; with sacct (history
    # kept in slurmdbd, which may lag) only after the longest patience. A job pending beyond
    # its limit (its resources ssw_pending_s, ssw_on_pending) stops the run or is reported.
    command = cluster.squeue_command(run_id)

    def waiting() -> list[str]:
        return sorted(_job_name(j) for j in list(scheduler.running) if not j.is_local)

    known: dict[str, tuple[str, Any]] = {}

    def limits() -> dict[str, tuple[str, Any]]:
        # the jobs submitted so far (the plugin empties its list while a status query runs:
        # what was known stays known)
        known.update({str(info.external_jobid): (_job_name(info.job),
                                                 pending_limit(info.job.resources))
                      for info in list(getattr(executor, "active_jobs", ()))
                      if info.external_jobid is not None and str(info.external_jobid)
                      not in known})
        return known

    def lost(message: str) -> None:
        from snakemake_interface_common.exceptions import WorkflowError

        scheduler.executor_error_callback(WorkflowError(message))

    def note(message: str) -> None:
        from snakemake.logging import logger

        logger.warning(f"ssw cluster check: {message}")

    stall_s = pause_s + timing.vanish_s + float(workflow.execution_settings.latency_wait)
    vanish_s = timing.vanish_s if used == "squeue" else stall_s
    cluster.watch_lost_jobs(lambda: cluster.query_jobs(command), waiting, lost, stall_s,
                            vanish_s, timing.poll_s, limits, note)
    return notes

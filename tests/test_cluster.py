"""ssw.cluster without a cluster: what the controller says, the status command a run needs,
and when a run's jobs count as lost. (tests/test_slurm.py runs the same on a real Slurm.)"""

from __future__ import annotations

import time

import pytest

from ssw import cluster as cl
from ssw import pending as pd
from ssw.errors import ConfigError, SswError

# `scontrol show config` of scripts/slurm-local.sh's cluster (Slurm 22.05), abridged.
NO_ACCOUNTING_CONFIG = """\
Configuration data as of 2026-01-01T00:00:00
AccountingStorageBackupHost = (null)
AccountingStorageType   = accounting_storage/none
ClusterName             = ssw-local
MinJobAge               = 300 sec
"""


def test_scontrol_config_is_parsed():
    info = cl.parse_scontrol_config(NO_ACCOUNTING_CONFIG)
    assert info == cl.SlurmConfig("accounting_storage/none", 300)
    assert not info.keeps_accounting
    slurmdbd = cl.parse_scontrol_config(
        "AccountingStorageType = accounting_storage/slurmdbd\nMinJobAge = 1h\n")
    assert slurmdbd.keeps_accounting and slurmdbd.min_job_age_s == 3600
    assert cl.parse_scontrol_config("MinJobAge = 5 min").min_job_age_s == 300


@pytest.mark.parametrize(("requested", "age", "init", "sacct", "used"), [
    ("sacct", 300, 40, True, "sacct"),
    ("squeue", 300, 40, True, "squeue"),    # 300 >= 3 x 40
    ("squeue", 100, 40, True, "sacct"),     # the plugin trades squeue for sacct
    ("squeue", None, 40, True, "sacct"),
    ("squeue", 100, 40, False, "squeue"),   # no sacct binary: squeue whatever
    ("sacct", 300, 40, False, "squeue"),
])
def test_effective_status_command_follows_the_plugin(requested, age, init, sacct, used):
    """The rule of snakemake-executor-plugin-slurm 2.8.0's check_active_jobs."""
    assert cl.effective_status_command(requested, age, init, sacct) == used


def test_without_accounting_the_status_command_becomes_squeue():
    info = cl.parse_scontrol_config(NO_ACCOUNTING_CONFIG)
    # the plugin's default where the sacct binary exists is sacct, which fails here
    assert cl.status_command(info, "sacct", 40, True) == "squeue"
    assert cl.status_command(info, "squeue", 40, True) == "squeue"
    # with accounting the run's own choice stays
    kept = cl.SlurmConfig("accounting_storage/slurmdbd", 300)
    assert cl.status_command(kept, "sacct", 40, True) == "sacct"
    assert cl.status_command(kept, "squeue", 40, True) == "squeue"


def test_a_first_status_delay_the_cluster_forgets_is_an_error_naming_the_flag():
    """MinJobAge 100 s < 3 x 40 s: the plugin would query sacct, which fails here."""
    short = cl.SlurmConfig(cl.NO_ACCOUNTING, 100)
    with pytest.raises(ConfigError, match="slurm-init-seconds-before-status-checks") as e:
        cl.status_command(short, "sacct", 40, True)
    assert "MinJobAge/3 = 33 s" in str(e.value) and "no job was submitted" in str(e.value)
    assert cl.status_command(short, "sacct", 30, True) == "squeue"
    assert cl.status_command(short, "sacct", 40, False) == "squeue"  # no sacct to trade for


def test_short_job_age_warns_only_for_squeue():
    assert cl.short_job_age(cl.SlurmConfig(cl.NO_ACCOUNTING, 300), "squeue") is None
    assert "MinJobAge = 150 s" in cl.short_job_age(cl.SlurmConfig(cl.NO_ACCOUNTING, 150),
                                                   "squeue")
    assert cl.short_job_age(cl.SlurmConfig("accounting_storage/slurmdbd", 150), "sacct") \
        is None


def test_job_states_are_parsed_from_squeue_and_sacct():
    assert cl.parse_job_states("12|RUNNING\n13|PENDING\n\n") == {"12": "RUNNING",
                                                                "13": "PENDING"}
    assert cl.parse_job_states("14|CANCELLED by 0\n15_2|COMPLETED\n") == {
        "14": "CANCELLED", "15_2": "COMPLETED"}
    # squeue_command's lines carry Slurm's reason (squeue -o %r; a reason may hold spaces)
    text = ("21|PENDING|JobHeldUser\n22|PENDING|ReqNodeNotAvail, UnavailableNodes:n1\n"
            "23|RUNNING|None\n")
    assert cl.parse_job_lines(text) == {
        "21": ("PENDING", "JobHeldUser"),
        "22": ("PENDING", "ReqNodeNotAvail, UnavailableNodes:n1"),
        "23": ("RUNNING", "None")}
    assert cl.parse_job_states(text) == {"21": "PENDING", "22": "PENDING", "23": "RUNNING"}
    cmd = cl.squeue_command("run-1")
    assert cmd[0] == "squeue" and "--format=%i|%T|%r" in cmd and cmd[-2:] == ["--name", "run-1"]


def test_a_jobs_pending_limit_comes_from_its_resources_or_the_defaults():
    assert pd.pending_limit({}) == pd.PendingLimit(pd.PENDING_LIMIT_S, pd.ON_PENDING)
    assert (pd.PENDING_LIMIT_S, pd.ON_PENDING) == (3600.0, "stop")
    assert pd.pending_limit({"ssw_pending_s": 90, "ssw_on_pending": "wait"}) == \
        pd.PendingLimit(90.0, "wait")
    assert pd.pending_limit({"ssw_on_pending": "'wait'"}).action == "wait"
    for res, field in [({"ssw_pending_s": 0}, "resources ssw_pending_s"),
                       ({"ssw_pending_s": "soon"}, "resources ssw_pending_s"),
                       ({"ssw_on_pending": "retry"}, "resources ssw_on_pending")]:
        with pytest.raises(ConfigError) as err:
            pd.pending_limit(res)
        assert err.value.field == field and "--set-resources" in str(err.value)


HELD = {"7": ("PENDING", "JobHeldUser"), "8": ("RUNNING", "None")}


def test_a_job_pending_beyond_its_limit_stops_the_run_with_squeues_reason():
    watch = pd.PendingWatch()
    limits = {"7": ("slow[i=0]", pd.PendingLimit(60, "stop"))}
    assert watch.step(0, HELD, limits) == (None, None)
    assert watch.step(59, HELD, limits) == (None, None)
    stop, note = watch.step(60, HELD, limits)
    assert note is None and stop is not None
    assert "slow[i=0] (Slurm job 7) pending for 60 s, limit 60 s" in stop
    assert "squeue's reason: JobHeldUser" in stop and "ssw_on_pending=wait" in stop
    assert "Slurm job 8" not in stop  # running: not pending


def test_a_waiting_run_reports_a_pending_job_once_per_limit():
    watch = pd.PendingWatch()
    limits = {"7": ("slow[i=0]", pd.PendingLimit(60, "wait"))}
    reports = [t for t in range(0, 200, 5) if watch.step(t, HELD, limits)[1] is not None]
    assert reports == [60, 120, 180]
    assert all(watch.step(t, HELD, limits)[0] is None for t in range(200, 300, 5))


def test_a_job_that_starts_is_forgotten_and_counts_anew_if_it_pends_again():
    watch = pd.PendingWatch()
    limits = {"7": ("a", pd.PendingLimit(60, "stop"))}
    assert watch.step(0, HELD, limits) == (None, None)
    assert watch.step(50, {"7": ("RUNNING", "None")}, limits) == (None, None)
    assert watch.step(55, HELD, limits) == (None, None)   # requeued: pending from 55
    assert watch.step(114, HELD, limits) == (None, None)
    assert watch.step(115, HELD, limits)[0] is not None
    # a pending job the run has no limit for: named by its id, the defaults
    watch = pd.PendingWatch()
    assert watch.step(0, HELD, {}) == (None, None)
    stop, _ = watch.step(pd.PENDING_LIMIT_S, HELD, {})
    assert stop is not None and "Slurm job 7 (Slurm job 7) pending for 3600 s" in stop


def test_the_watch_thread_stops_a_run_whose_job_pends_beyond_its_limit():
    got, notes = [], []
    thread = cl.watch_lost_jobs(lambda: dict(HELD), lambda: ["slow[i=0]", "slow[i=1]"],
                                got.append, stall_s=100, vanish_s=100, poll_s=0.02,
                                limits=lambda: {"7": ("slow[i=0]", pd.PendingLimit(0.1,
                                                                                  "stop"))},
                                on_note=notes.append)
    thread.join(timeout=5)
    assert not thread.is_alive() and len(got) == 1 and not notes
    assert "slow[i=0] (Slurm job 7)" in got[0] and "JobHeldUser" in got[0]


def test_the_watch_thread_reports_a_pending_job_and_waits():
    got, notes = [], []
    cl.watch_lost_jobs(lambda: dict(HELD), lambda: ["slow[i=0]"], got.append, stall_s=100,
                       vanish_s=100, poll_s=0.02,
                       limits=lambda: {"7": ("slow[i=0]", pd.PendingLimit(0.1, "wait"))},
                       on_note=notes.append)
    time.sleep(0.5)
    assert not got and 2 <= len(notes) <= 6, notes
    assert "JobHeldUser" in notes[0] and "The run waits" in notes[0]


def test_a_jobs_limit_that_is_not_allowed_stops_the_run_naming_the_resource():
    got = []
    thread = cl.watch_lost_jobs(
        lambda: dict(HELD), lambda: ["a"], got.append, stall_s=100, vanish_s=100,
        poll_s=0.02, limits=lambda: {"7": ("a", pd.pending_limit({"ssw_pending_s": -1}))})
    thread.join(timeout=5)
    assert len(got) == 1 and "ssw_pending_s" in got[0]


def test_vanished_jobs_are_lost_after_the_grace_not_before():
    watch = cl.LostJobsWatch(vanish_s=60, stall_s=300)
    jobs = ["a (i=0)", "a (i=1)"]
    assert watch.step(0, jobs, {"1": "RUNNING", "2": "PENDING"}) is None
    assert watch.step(10, jobs, {}) is None           # gone: the grace starts
    assert watch.step(69, jobs, {}) is None
    msg = watch.step(70, jobs, {})
    assert msg is not None and "Slurm lists no job of this run" in msg
    assert "2 cluster job(s): a (i=0), a (i=1)" in msg and "MinJobAge" in msg


def test_a_failed_query_or_a_running_job_resets_nothing_or_everything():
    watch = cl.LostJobsWatch(vanish_s=60, stall_s=300)
    assert watch.step(0, ["a"], {}) is None
    assert watch.step(100, ["a"], None) is None       # the query failed: no verdict
    assert watch.step(101, ["a"], {}) is not None     # ... but the absence still counts
    watch = cl.LostJobsWatch(vanish_s=60, stall_s=300)
    assert watch.step(0, ["a"], {}) is None
    assert watch.step(50, ["a"], {"7": "RUNNING"}) is None   # a job appeared: reset
    assert watch.step(100, ["a"], {}) is None
    assert watch.step(159, ["a"], {}) is None
    assert watch.step(0, [], {}) is None              # nothing awaited: reset
    assert watch.step(200, ["a"], {}) is None


def test_ended_jobs_the_plugin_no_longer_reports_are_lost_after_its_longest_pause():
    watch = cl.LostJobsWatch(vanish_s=60, stall_s=300)
    done = {"5": "COMPLETED", "6": "FAILED"}
    assert watch.step(0, ["b"], done) is None
    assert watch.step(299, ["b"], done) is None
    msg = watch.step(300, ["b"], done)
    assert msg is not None and "5 COMPLETED, 6 FAILED" in msg
    # PREEMPTED without requeue is final: the plugin would keep waiting for it
    watch = cl.LostJobsWatch(vanish_s=60, stall_s=10)
    assert watch.step(0, ["b"], {"5": "PREEMPTED"}) is None
    assert watch.step(10, ["b"], {"5": "PREEMPTED"}) is not None


def test_the_watch_thread_calls_back_once_and_ends():
    got = []
    states = iter([{"1": ("RUNNING", "None")}, {}, {}, {}, {}, {}])
    thread = cl.watch_lost_jobs(lambda: next(states), lambda: ["job"], got.append,
                                stall_s=100, vanish_s=0.05, poll_s=0.02)
    thread.join(timeout=5)
    assert not thread.is_alive() and len(got) == 1 and "job" in got[0]
    time.sleep(0.05)
    assert len(got) == 1


def test_sinfo_gives_the_largest_node():
    assert cl.parse_sinfo("2 1000\n4+ 800\n") == cl.NodeLimits(4, 1000)
    with pytest.raises(SswError):
        cl.parse_sinfo("")


def test_the_status_pause_comes_from_the_environment_within_the_plugins_own():
    assert cl.slurm_timing({}).status_pause_s == cl.STATUS_PAUSE_MAX_S == 30.0
    assert cl.slurm_timing({"SSW_SLURM_STATUS_MAX_S": " 2 "}).status_pause_s == 2.0
    assert cl.slurm_timing({"SSW_SLURM_STATUS_MAX_S": "600"}).status_pause_s == 180.0
    for raw in ("often", "0", "-1", "inf"):
        with pytest.raises(ConfigError) as err:
            cl.slurm_timing({"SSW_SLURM_STATUS_MAX_S": raw})
        assert err.value.field == "SSW_SLURM_STATUS_MAX_S" and "seconds" in str(err.value)
    assert "(30 s)" in cl.short_job_age(cl.SlurmConfig(cl.NO_ACCOUNTING, 20), "squeue", 30.0)
    assert cl.short_job_age(cl.SlurmConfig(cl.NO_ACCOUNTING, 150), "squeue", 30.0) is None


class _PluginLike:
    """The Slurm plugin's pause rule (2.8.0, ``check_active_jobs``): after a query, the
    initial pause when a job ended, else 10 s more, up to 180 s."""

    def __init__(self) -> None:
        self.next_seconds_between_status_checks = 1.0

    async def check_active_jobs(self, active_jobs):
        still = [j for j in active_jobs if j != "ended"]
        for j in still:
            yield j
        pause = self.next_seconds_between_status_checks
        self.next_seconds_between_status_checks = (
            1.0 if len(still) < len(active_jobs) else min(pause + 10.0, 180.0))


def test_the_pause_between_status_queries_stops_growing_at_the_cap():
    import asyncio

    from ssw.workflow import cap_status_pause

    async def query(executor, jobs):
        return [j async for j in executor.check_active_jobs(jobs)]

    free, capped = _PluginLike(), _PluginLike()
    cap_status_pause(capped, 25.0)
    pauses = []
    for jobs in (["a", "b"], ["a", "b"], ["a", "b"], ["a", "ended"], ["a"], ["a"], ["a"]):
        assert asyncio.run(query(capped, jobs)) == asyncio.run(query(free, jobs))
        pauses.append((free.next_seconds_between_status_checks,
                       capped.next_seconds_between_status_checks))
    assert pauses == [(11.0, 11.0), (21.0, 21.0), (31.0, 25.0), (1.0, 1.0), (11.0, 11.0),
                      (21.0, 21.0), (31.0, 25.0)]


class _RemoteLike:
    """The remote executor's bookkeeping (snakemake-interface-executor-plugins 9.x,
    ``RemoteExecutor``): each status check takes every job out of ``active_jobs`` for its query
    and puts back those the query yields; ``cancel`` (Ctrl-C) passes what ``active_jobs``
    holds to the plugin's ``cancel_jobs``. ``interrupt_at`` the job of the query at which a
    Ctrl-C arrives (None: none)."""

    def __init__(self, jobs, interrupt_at=None) -> None:
        self.active_jobs, self.cancelled, self.interrupt_at = list(jobs), [], interrupt_at

    async def check_active_jobs(self, active_jobs):
        for job in active_jobs:
            if job == self.interrupt_at:
                self.cancel()
            if job != "ended":
                yield job

    def cancel_jobs(self, active_jobs) -> None:
        self.cancelled += active_jobs

    def cancel(self) -> None:
        self.cancel_jobs(list(self.active_jobs))

    def status_check(self) -> None:
        import asyncio

        async def query():
            return [j async for j in self.check_active_jobs(jobs)]

        jobs = list(self.active_jobs)
        self.active_jobs.clear()
        self.active_jobs.extend(asyncio.run(query()))


def test_a_ctrl_c_during_a_status_query_cancels_the_jobs_it_holds():
    """The executor's list is empty while a status query runs: a Ctrl-C then cancelled
    nothing and left the run's jobs on the cluster; with :func:`cancel_in_flight` it
    cancels every job of the run, each once, and not those the query saw end."""
    from ssw.workflow import cancel_in_flight

    bare = _RemoteLike(["a", "b"], interrupt_at="b")
    bare.status_check()
    assert bare.cancelled == []  # the race itself
    fixed = _RemoteLike(["a", "b"], interrupt_at="b")
    cancel_in_flight(fixed)
    fixed.status_check()
    assert fixed.cancelled == ["a", "b"]
    after = _RemoteLike(["a", "ended", "b"])
    cancel_in_flight(after)
    after.status_check()
    after.cancel()
    assert after.cancelled == ["a", "b"]


def test_the_watch_timing_comes_from_the_environment_or_the_defaults():
    assert cl.slurm_timing({})[:2] == (cl.VANISH_GRACE_S, cl.WATCH_POLL_S) == (60.0, 15.0)
    assert cl.slurm_timing({"SSW_SLURM_VANISH_GRACE_S": "600",
                            "SSW_SLURM_WATCH_POLL_S": " 30 "})[:2] == (600.0, 30.0)
    for env, field in [({"SSW_SLURM_VANISH_GRACE_S": "soon"}, "SSW_SLURM_VANISH_GRACE_S"),
                       ({"SSW_SLURM_VANISH_GRACE_S": "-5"}, "SSW_SLURM_VANISH_GRACE_S"),
                       ({"SSW_SLURM_WATCH_POLL_S": "inf"}, "SSW_SLURM_WATCH_POLL_S"),
                       ({"SSW_SLURM_WATCH_POLL_S": "90"}, "SSW_SLURM_WATCH_POLL_S")]:
        with pytest.raises(ConfigError) as err:
            cl.slurm_timing(env)
        assert err.value.field == field and "seconds" in str(err.value)

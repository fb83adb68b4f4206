"""LocalPoolExecutor: units in threads, at most ``workers`` at a time, study workers passed on."""

from __future__ import annotations

import os
import signal
import threading
import time
from pathlib import Path

import pytest

from simlunar.pipeline.executors import LocalPoolExecutor, SerialExecutor

#: wall-clock limit that catches a hang (Dask waiting forever) without failing on a busy
#: 2-core CI machine: the behaviour is checked by the messages, not by the seconds
HANG_S = 60


class _Probe:
    """A unit function that records how many calls overlap and what it was given."""

    def __init__(self):
        self.lock = threading.Lock()
        self.active = 0
        self.peak = 0
        self.kwargs = []

    def __call__(self, payload, *, study_workers=1, progress=None):
        with self.lock:
            self.active += 1
            self.peak = max(self.peak, self.active)
            self.kwargs.append({"study_workers": study_workers, "progress": progress})
        time.sleep(0.05)
        with self.lock:
            self.active -= 1
        return payload * 10


def test_pool_runs_workers_units_at_a_time_and_passes_study_workers():
    probe = _Probe()
    out = dict(LocalPoolExecutor(2).run(probe, list(range(6))))
    assert out == {i: i * 10 for i in range(6)}
    assert probe.peak == 2
    assert all(k["study_workers"] == 2 and k["progress"] is None for k in probe.kwargs)


def test_single_unit_keeps_parallel_study_and_progress():
    probe = _Probe()

    def hook(stage, done, total):
        pass

    assert list(LocalPoolExecutor(3).run(probe, [4], progress=hook)) == [(0, 40)]
    assert probe.kwargs == [{"study_workers": 3, "progress": hook}]


def test_functions_without_study_workers_still_run():
    assert dict(LocalPoolExecutor(2).run(lambda p: p + 1, [1, 2, 3])) == {0: 2, 1: 3, 2: 4}


def test_one_worker_is_serial_in_order():
    probe = _Probe()
    assert list(LocalPoolExecutor(1).run(probe, [1, 2])) == list(
        SerialExecutor().run(probe, [1, 2])
    )
    assert probe.peak == 1 and probe.kwargs[0]["study_workers"] == 1


def test_a_failing_unit_propagates():
    def boom(p):
        if p == 1:
            raise RuntimeError("unit 1 failed")
        return p

    with pytest.raises(RuntimeError, match="unit 1 failed"):
        list(LocalPoolExecutor(2).run(boom, [0, 1, 2, 3]))


def test_bad_worker_count():
    with pytest.raises(ValueError, match="--workers must be >= 1"):
        LocalPoolExecutor(0)


# --------------------------------------------------------------------------- Dask faults
SCHEDULER_ADDRESSES = [
    ("tcp://127.0.0.1:8786", ("tcp", "127.0.0.1", 8786)),
    ("tls://scheduler.example:8786", ("tls", "scheduler.example", 8786)),
    ("node-3:8786", ("tcp", "node-3", 8786)),
    ("tcp://[::1]:8786", ("tcp", "::1", 8786)),
]
BAD_ADDRESSES = ["not a url", "tcp://host", "http://host:8786", "tcp://host:0", "tcp://:8786", ""]


def test_scheduler_addresses_are_parsed_and_bad_ones_rejected_before_connecting():
    from simlunar.errors import ConfigError
    from simlunar.pipeline.executors import DaskExecutor, parse_scheduler_address

    for address, parsed in SCHEDULER_ADDRESSES:
        assert parse_scheduler_address(address) == parsed
    for address in BAD_ADDRESSES:
        with pytest.raises(ConfigError, match="not a scheduler address"):
            DaskExecutor(address)  # raises in the constructor: nothing is connected


def test_a_closed_port_fails_at_once_with_one_line():
    from simlunar.errors import ConfigError
    from simlunar.pipeline.executors import DaskExecutor

    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=r"^--scheduler tcp://127.0.0.1:9: cannot connect"):
        DaskExecutor("tcp://127.0.0.1:9").open()
    assert time.perf_counter() - t0 < HANG_S  # generous (a busy CI machine); catches a hang


def test_a_listener_that_is_not_a_dask_scheduler_fails_within_the_timeout():
    """Dask's own Client waits forever on a server that never answers its handshake."""
    import socket

    from simlunar.errors import ConfigError
    from simlunar.pipeline.executors import DaskExecutor

    with socket.create_server(("127.0.0.1", 0)) as server:
        port = server.getsockname()[1]
        t0 = time.perf_counter()
        with pytest.raises(
            ConfigError, match=r"does not answer like a Dask scheduler within 0\.5 s"
        ):
            DaskExecutor(f"tcp://127.0.0.1:{port}", timeout_s=0.5).open()
        assert time.perf_counter() - t0 < HANG_S


def _cfg():
    from simlunar.config.schema import ExperimentCfg

    return ExperimentCfg.model_validate(
        {
            "name": "dask_faults",
            "seed": 2,
            "terrain": {"preset": "aerial_1", "scale": 0.125},
            "study": {"strategies": ["random", "grid"], "densities": [0.5], "trials": 2},
            "sweep": {"render.light.elevation_deg": [10, 30, 50, 70]},
        }
    )


def _after_first_unit(out, action):
    """Run ``action()`` in a thread once the first unit of ``out`` is finished."""

    def watch():
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            units = out / "units"
            if units.is_dir() and any(not p.name.startswith(".") for p in units.glob("*.json")):
                action()
                return
            time.sleep(0.02)

    t = threading.Thread(target=watch, daemon=True)
    t.start()
    return t


def _run(out, executor):
    from fake_unit import fake_unit

    from simlunar.pipeline.runner import run_experiment

    return run_experiment(
        _cfg(), out, executor=executor, compute=fake_unit, progress=False, figures=False
    )


@pytest.mark.slow
def test_dask_killing_the_only_worker_mid_sweep_reruns_its_unit_on_a_new_worker(
    tmp_path, monkeypatch
):
    """A worker process killed with SIGKILL: its nanny starts a new one, the scheduler gives
    it the lost unit, the run finishes with the results of a serial run."""
    import distributed

    from simlunar.pipeline.executors import DaskExecutor

    here = str(Path(__file__).resolve().parent)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([here, os.environ.get("PYTHONPATH", "")]))
    monkeypatch.setenv("SIMLUNAR_TEST_DELAY", "0.5")
    _run(tmp_path / "serial", LocalPoolExecutor(1))
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster, set_as_default=False) as c:
            (pid,) = c.run(os.getpid).values()
        out = tmp_path / "dask"
        watcher = _after_first_unit(out, lambda: os.kill(pid, signal.SIGKILL))
        s = _run(out, DaskExecutor(cluster.scheduler_address, worker_wait_s=30, poll_s=0.2))
        watcher.join()
    assert s.units_computed == 4
    assert (out / "results.csv").read_bytes() == (tmp_path / "serial" / "results.csv").read_bytes()


def test_dask_losing_every_worker_stops_within_the_stated_wait_and_keeps_finished_units(
    tmp_path, monkeypatch
):
    import distributed

    from simlunar.errors import InfrastructureError
    from simlunar.pipeline.executors import DaskExecutor

    monkeypatch.setenv("SIMLUNAR_TEST_DELAY", "0.3")
    cluster = distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    )
    try:
        out = tmp_path / "out"
        _after_first_unit(out, lambda: cluster.scale(0))
        ex = DaskExecutor(cluster.scheduler_address, worker_wait_s=1.5, poll_s=0.2)
        t0 = time.perf_counter()
        with pytest.raises(InfrastructureError) as err:
            _run(out, ex)
        elapsed = time.perf_counter() - t0
    finally:
        cluster.close()
    msg = str(err.value)
    assert msg.startswith(f"--scheduler {cluster.scheduler_address}: no worker connected for 1.5 s")
    kept = [p for p in (out / "units").glob("*.json") if not p.name.startswith(".")]
    assert 1 <= len(kept) < 4
    assert f"{len(kept)} of 4 units finished and kept in {out / 'units'}" in msg
    assert elapsed < HANG_S  # worker_wait_s=1.5; Dask alone would wait forever
    assert not (out / "results.csv").exists()


@pytest.mark.slow
def test_dask_killing_the_scheduler_is_one_error_naming_it_and_keeps_finished_units(tmp_path):
    """A real scheduler and worker (``dask scheduler``, ``dask worker``) in their own
    processes; the scheduler is SIGKILLed after the first unit."""
    import json
    import subprocess
    import sys

    from simlunar.errors import InfrastructureError
    from simlunar.pipeline.executors import DaskExecutor

    here = str(Path(__file__).resolve().parent)
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([here, os.environ.get("PYTHONPATH", "")]),
        "SIMLUNAR_TEST_DELAY": "0.3",
    }
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    info = tmp_path / "scheduler.json"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env}
    sched = subprocess.Popen(
        [*dask, "--host", "127.0.0.1", "--port", "0", "--scheduler-file", str(info), "--no-dashboard"],
        **quiet,
    )  # fmt: skip
    worker = None
    try:
        deadline = time.monotonic() + 60
        while not info.is_file() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        worker = subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
             "--no-nanny", "--no-dashboard"],
            **quiet,
        )  # fmt: skip
        out = tmp_path / "out"
        _after_first_unit(out, lambda: os.kill(sched.pid, signal.SIGKILL))
        t0 = time.perf_counter()
        with pytest.raises(InfrastructureError) as err:
            _run(out, DaskExecutor(address, worker_wait_s=600, poll_s=0.2))
        elapsed = time.perf_counter() - t0
    finally:
        for p in (sched, worker):
            if p is not None:
                p.kill()
                p.wait()
    msg = str(err.value)
    assert msg.startswith(f"--scheduler {address}: lost the connection to the scheduler")
    assert "\n" not in msg
    kept = [p for p in (out / "units").glob("*.json") if not p.name.startswith(".")]
    assert 1 <= len(kept) < 4 and f"{len(kept)} of 4 units finished" in msg
    assert elapsed < 2 * HANG_S  # found lost, not waited out (worker_wait_s=600)


def test_a_server_talking_garbage_is_one_line_within_the_connect_timeout():
    """A server that sends bytes at once (an HTTP banner, noise) passes a plain connect and
    used to leave Dask's Client waiting for its own timeout, then a traceback."""
    import socket
    import threading

    from simlunar.errors import ConfigError
    from simlunar.pipeline.executors import DaskExecutor

    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    port = srv.getsockname()[1]

    def serve():
        try:
            while True:
                c, _ = srv.accept()
                c.sendall(b"HTTP/1.0 200 OK\r\n\r\n" + b"\x00garbage" * 50)
                c.close()
        except OSError:
            pass

    threading.Thread(target=serve, daemon=True).start()
    t0 = time.monotonic()
    try:
        with pytest.raises(ConfigError) as err:
            DaskExecutor(f"tcp://127.0.0.1:{port}", timeout_s=2.0).open()
    finally:
        srv.close()
    assert time.monotonic() - t0 < 2.0 + 1.0
    msg = str(err.value)
    assert "\n" not in msg
    assert msg == (
        f"--scheduler tcp://127.0.0.1:{port}: something listens there but it does not speak "
        "Dask's protocol (not a Dask scheduler)"
    )

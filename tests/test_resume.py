"""Determinism and resume: identical runs give identical metrics; a run killed at random moments and resumed ends
with the same metrics.csv as an uninterrupted one; run directories are never shared or overwritten."""

from __future__ import annotations

import csv
import logging
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from curiosity.errors import CheckpointError, RunDirectoryError
from curiosity.runtime.checkpoint import load_checkpoint, save_checkpoint
from curiosity.runtime.logger import is_wall_clock
from curiosity.runtime.loop import run
from tests.conftest import REPO, compose_cfg, holding_lock, run_cli

ARGS = ["budget=smoke", "budget.max_steps=120", "budget.warmup_steps=40", "env.renderer=fast", "deterministic=true",
        "planner.horizon=3",  # 27 sequences: what is tested here is resuming, not planning; keeps the suite short
        "checkpoint_every=20", "log_every=10", "seed=3"]  # fmt: skip


def metrics_without_wall_clock(run_dir: Path) -> list[list[str]]:
    """metrics.csv rows as text, without the columns that measure the machine."""
    with (run_dir / "metrics.csv").open(newline="") as f:
        rows = list(csv.reader(f))
    keep = [i for i, c in enumerate(rows[0]) if not is_wall_clock(c)]
    return [[row[i] for i in keep] for row in rows]


def _rows(path: Path) -> int:
    try:
        return sum(1 for _ in path.open()) - 1
    except FileNotFoundError:
        return -1


def test_same_seed_same_metrics_and_killed_runs_resume_to_the_same_metrics(tmp_path: Path, monkeypatch) -> None:
    first, second, killed = tmp_path / "first", tmp_path / "second", tmp_path / "killed"
    for out in (first, second):
        if out == second:  # glibc's default mmap threshold, fixed: the run leaves its allocator alone (allocator.py)
            monkeypatch.setenv("MALLOC_MMAP_THRESHOLD_", "131072")
        res = run_cli([*ARGS, f"hydra.run.dir={out}"], cwd=tmp_path)
        assert res.returncode == 0, res.stderr[-2000:]
    monkeypatch.delenv("MALLOC_MMAP_THRESHOLD_")
    reference = metrics_without_wall_clock(first)
    assert len(reference) == 13  # header + steps 10..120
    # where memory comes from changes no number: the second run left glibc's allocator at its defaults
    assert metrics_without_wall_clock(second) == reference  # exact: determinism (same config, seed and machine)

    # Kill -9 after the rows of env steps 30, 70 and 100 are written (wherever the run is then), resume each time.
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    cmd = [sys.executable, "-m", "runners.train", *ARGS, "progress=false", f"hydra.run.dir={killed}"]
    kills = 0
    for kill_after_rows in (3, 7, 10):
        proc = subprocess.Popen(cmd, cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.time() + 300
        while proc.poll() is None and _rows(killed / "metrics.csv") < kill_after_rows and time.time() < deadline:
            time.sleep(0.02)
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
            kills += 1
        proc.wait()
    res = run_cli([*ARGS, f"hydra.run.dir={killed}"], cwd=tmp_path)  # resume to the end
    assert res.returncode == 0, res.stderr[-2000:]
    assert kills >= 2
    assert metrics_without_wall_clock(killed) == reference  # exact: resumed = uninterrupted, on one machine
    steps = [int(r[0]) for r in metrics_without_wall_clock(killed)[1:]]
    assert steps == sorted(set(steps))  # no step twice, none missing
    saved = load_checkpoint(killed)
    assert saved["cpu_seconds"] > 0  # CPU time is carried through the resumes (summed, like wall_seconds)

    # A truncated last checkpoint: the run resumes from the one before (step 100) and ends with the same file again.
    newest = killed / "checkpoint.pt"
    newest.write_bytes(newest.read_bytes()[:1000])
    res = run_cli([*ARGS, f"hydra.run.dir={killed}"], cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "resuming from checkpoint.prev.pt at env step 100" in res.stdout + res.stderr
    assert metrics_without_wall_clock(killed) == reference  # exact: determinism on one machine, as promised


def test_an_unreadable_checkpoint_falls_back_to_the_previous_one(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    for step in (10, 20):
        save_checkpoint(tmp_path, {"config": {}, "step": step, "finished": False})
    assert load_checkpoint(tmp_path)["step"] == 20 and (tmp_path / "checkpoint.prev.pt").is_file()
    newest = tmp_path / "checkpoint.pt"
    newest.write_bytes(newest.read_bytes()[:100])
    with caplog.at_level(logging.WARNING):
        assert load_checkpoint(tmp_path)["step"] == 10
    assert "resuming from checkpoint.prev.pt at env step 10" in caplog.text
    (tmp_path / "checkpoint.prev.pt").write_bytes(b"")
    with pytest.raises(CheckpointError, match=r"checkpoint\.pt: cannot be read") as info:
        load_checkpoint(tmp_path)
    assert "EOFError" in str(info.value) and "move the run directory away" in str(info.value)


def test_a_run_directory_of_another_config_is_refused(tmp_path: Path) -> None:
    cfg = compose_cfg([*ARGS, "budget.max_steps=50", "deterministic=false"])
    run(cfg, tmp_path)
    with pytest.raises(RunDirectoryError, match="another configuration"):
        run(compose_cfg([*ARGS, "budget.max_steps=50", "seed=4"]), tmp_path)
    with pytest.raises(RunDirectoryError, match="resume=false"):
        run(compose_cfg([*ARGS, "budget.max_steps=50", "deterministic=false", "resume=false"]), tmp_path)
    again = run(compose_cfg([*ARGS, "budget.max_steps=50", "deterministic=false", "progress=true"]), tmp_path)
    assert again.env_steps == 50  # the same run, complete: returned as it is


def test_a_run_made_before_a_key_existed_resumes_when_the_key_keeps_what_it_did(tmp_path: Path) -> None:
    """A checkpoint whose config lacks a key added since (here ``agent.updates``) resumes when the key has the value
    that reproduces the old run (``LEGACY``: ``joint``), and is refused under another value."""
    import torch

    cfg = compose_cfg([*ARGS, "budget.max_steps=50"])
    run(cfg, tmp_path)
    ckpt = torch.load(tmp_path / "checkpoint.pt", weights_only=False)
    del ckpt["config"]["agent"]["updates"]
    save_checkpoint(tmp_path, ckpt)  # a finished run: its config is checked before it is returned as complete
    with pytest.raises(RunDirectoryError, match=r"agent\.updates: None there, 'nsrs' now"):
        run(compose_cfg([*ARGS, "budget.max_steps=50", "agent.updates=nsrs"]), tmp_path)
    assert run(cfg, tmp_path).env_steps == 50


def test_a_directory_with_a_run_but_no_checkpoint_is_not_overwritten(tmp_path: Path) -> None:
    (tmp_path / "metrics.csv").write_text("step\n1\n")
    with pytest.raises(RunDirectoryError, match="without a checkpoint"):
        run(compose_cfg(ARGS), tmp_path)
    assert (tmp_path / "metrics.csv").read_text() == "step\n1\n"


def test_a_finished_run_kept_without_its_checkpoint_is_complete_and_left_as_it_was(tmp_path: Path) -> None:
    """Committed results keep ``.hydra/``, ``metrics.csv`` and ``summary.json``, not checkpoints: the same command
    again (a sweep preset re-run in a fresh clone) finds that run complete; another configuration is refused."""
    from omegaconf import OmegaConf

    args = [*ARGS, "budget.max_steps=50"]
    out = tmp_path / "sweep" / "run"
    summary = run(compose_cfg(args), out)
    (out / ".hydra").mkdir()
    (out / ".hydra" / "config.yaml").write_text(OmegaConf.to_yaml(compose_cfg(args)))  # as the job writes it
    for name in ("checkpoint.pt", "checkpoint.prev.pt"):
        (out / name).unlink(missing_ok=True)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}

    assert run(compose_cfg([*args, "progress=true"]), out) == summary  # volatile keys may differ
    with pytest.raises(RunDirectoryError, match=r"finished run of another configuration \(seed: 3 there, 4 now\)"):
        run(compose_cfg([*args, "seed=4"]), out)
    with pytest.raises(RunDirectoryError, match="resume=false"):
        run(compose_cfg([*args, "resume=false"]), out)
    res = run_cli(["-m", *args, f"hydra.sweep.dir={out.parent}", "hydra.sweep.subdir=run"], cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "already complete" in res.stdout + res.stderr
    assert not (out.parent / "failed_jobs.txt").exists()
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != "train.log"} == {
        p: b for p, b in before.items() if p.name != "train.log"}  # fmt: skip


def test_a_live_writer_locks_its_run_directory(tmp_path: Path) -> None:
    with holding_lock(tmp_path) as pid:
        with pytest.raises(RunDirectoryError, match=f"being written by process {pid}"):
            run(compose_cfg(ARGS), tmp_path)
    assert (tmp_path / "run.lock").read_text() == str(pid)  # the dead owner's file is still there, its lock is not
    assert run(compose_cfg([*ARGS, "budget.max_steps=50"]), tmp_path).env_steps == 50  # a dead owner's lock is stale


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_checkpoints_says_so_in_one_line_and_the_same_command_resumes(tmp_path: Path, signum: int) -> None:
    out = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    cmd = [sys.executable, "-m", "runners.train", *ARGS, "progress=false", f"hydra.run.dir={out}"]
    proc = subprocess.Popen(cmd, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    while proc.poll() is None and _rows(out / "metrics.csv") < 5:
        time.sleep(0.02)
    proc.send_signal(signum)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signum, stderr[-2000:]
    assert "Traceback" not in stdout + stderr
    step = _rows(out / "metrics.csv")  # the run stops at the step after the signal, not necessarily on a row
    assert re.fullmatch(r"interrupted at step (\d+), checkpoint written; run the same command again to resume",
                        stderr.strip().splitlines()[-1]), stderr[-2000:]  # fmt: skip
    assert int(stderr.strip().splitlines()[-1].split()[3].rstrip(",")) >= 10 * step
    log = (out / "train.log").read_text()
    assert "running in" in log and f"signal {int(signum)} at env step" in log  # the run's log lines
    res = run_cli([*ARGS, f"hydra.run.dir={out}"], cwd=tmp_path)
    assert res.returncode == 0 and "resuming" in res.stdout + res.stderr
    assert int(metrics_without_wall_clock(out)[-1][0]) == 120


def _state(pid: int) -> str:
    """The kernel's one-letter state of process ``pid`` (Z: a zombie, dead and not yet reaped)."""
    return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]


def _start_run(out: Path, cwd: Path, rows: int) -> subprocess.Popen:
    """A run of ``ARGS`` into ``out`` in a child process, returned once it has written ``rows`` metrics rows."""
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    cmd = [sys.executable, "-m", "runners.train", *ARGS, "progress=false", f"hydra.run.dir={out}"]
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 300
    while proc.poll() is None and _rows(out / "metrics.csv") < rows and time.time() < deadline:
        time.sleep(0.02)
    return proc


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads process states from /proc (Linux)")
def test_a_run_killed_with_sigkill_resumes_before_its_process_is_reaped(tmp_path: Path) -> None:
    # The killed child stays a zombie until this test reaps it; a zombie still answers kill(pid, 0), so a pid-file lock
    # refused the resume ("being written by process N"). The kernel's lock died with the process: the resume starts.
    out = tmp_path / "run"
    proc = _start_run(out, tmp_path, rows=5)
    try:
        assert proc.poll() is None, "the run ended before it could be killed"
        os.kill(proc.pid, signal.SIGKILL)  # not proc.kill(): Popen must not reap it
        while _state(proc.pid) != "Z":
            time.sleep(0.01)
        assert (out / "run.lock").read_text() == str(proc.pid)  # the dead run's lock file is still there
        res = run_cli([*ARGS, f"hydra.run.dir={out}"], cwd=tmp_path)
        assert _state(proc.pid) == "Z"  # still not reaped while the resume ran
    finally:
        proc.wait()
    assert res.returncode == 0, res.stderr[-2000:]
    assert "resuming" in res.stdout + res.stderr
    assert (out / "summary.json").is_file() and not (out / "run.lock").exists()


def test_a_live_run_s_directory_is_refused_in_one_line(tmp_path: Path) -> None:
    out = tmp_path / "run"
    proc = _start_run(out, tmp_path, rows=2)
    try:
        assert proc.poll() is None, "the run ended before the second command"
        res = run_cli([*ARGS, f"hydra.run.dir={out}"], cwd=tmp_path)
    finally:
        proc.kill()
        proc.wait()
    assert res.returncode != 0
    assert f"is being written by process {proc.pid}" in res.stderr and "Traceback" not in res.stderr

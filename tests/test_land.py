"""``python -m runners.land``: finished runs of another clone land in results/ with only the files results keep;
what DEST holds is never changed or lost by a refused or repeated landing."""

from __future__ import annotations

from pathlib import Path

import pytest

from runners.land import KEPT, land, main, report
from tests.conftest import holding_lock


def make_run(root: Path, rel: str, config: str = "seed: 1\n", finished: bool = True, steps: int = 5) -> Path:
    """A run directory as a sweep leaves it: Hydra's files, metrics, log, events, checkpoints and its lock."""
    run = root / rel
    (run / ".hydra").mkdir(parents=True)
    (run / ".hydra/config.yaml").write_text(config)
    (run / ".hydra/overrides.yaml").write_text("- seed=1\n")
    (run / "metrics.csv").write_text("step,x\n" + "".join(f"{i},{i * 0.5}\n" for i in range(steps)))
    (run / "train.log").write_text("running\n")
    (run / "tb").mkdir()
    (run / "tb/events.out.tfevents.1.vm").write_bytes(b"\x00\x01events")
    (run / "checkpoint.pt").write_bytes(b"big")
    (run / "checkpoint.prev.pt").write_bytes(b"big")
    (run / "checkpoints").mkdir()
    (run / "checkpoints/step=100.pt").write_bytes(b"big")
    if finished:
        (run / "summary.json").write_text(f'{{"steps_to_goal": {steps}}}\n')
    return run


def snapshot(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture
def src(tmp_path: Path) -> Path:
    s = tmp_path / "wt/results/table2"
    make_run(s, "mc/rnd/seed=100")
    make_run(s, "mc/rnd/seed=101", config="seed: 101\n", finished=False)
    (s / "multirun.yaml").write_text("sweep\n")
    return s


def test_finished_runs_land_with_only_the_kept_files(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "main/results/table2"
    p = land(src, dest)
    assert p.copy == [Path("mc/rnd/seed=100")] and p.unfinished == [Path("mc/rnd/seed=101")]
    run = dest / "mc/rnd/seed=100"
    assert sorted(c.name for c in run.iterdir()) == sorted(KEPT)  # no events, checkpoint, lock or kept checkpoints
    assert "tb" not in KEPT  # TensorBoard's events repeat metrics.csv: results/ never holds them
    assert snapshot(run) == {k: v for k, v in snapshot(src / "mc/rnd/seed=100").items() if k.split("/")[0] in KEPT}
    assert not (dest / "mc/rnd/seed=101").exists()  # unfinished: left in SRC
    assert not (dest / "multirun.yaml").exists()  # a preset's launches each rewrite it; every run has its .hydra/
    assert not list(dest.rglob("*.landing")) and not list(dest.rglob("*.replaced"))

    # landing again changes nothing, also after a re-launch appended to the source's train.log
    before = snapshot(dest)
    (src / "mc/rnd/seed=100/train.log").write_text("running\nalready complete\n")
    p = land(src, dest)
    assert p.copy == [] and p.same == [Path("mc/rnd/seed=100")]
    assert snapshot(dest) == before


def test_a_stopped_copy_is_completed_and_unfinished_runs_land_when_asked(src: Path, tmp_path: Path) -> None:
    dest = tmp_path / "dest"
    make_run(dest, "mc/rnd/seed=100", finished=False, steps=2)  # committed earlier, stopped at step 2
    p = land(src, dest, unfinished=True)
    assert p.complete == [Path("mc/rnd/seed=100")]
    assert (dest / "mc/rnd/seed=100/summary.json").is_file()
    assert not (dest / "mc/rnd/seed=100/checkpoint.pt").exists()  # the old copy's files are replaced, not merged
    assert (dest / "mc/rnd/seed=100/metrics.csv").read_bytes() == (src / "mc/rnd/seed=100/metrics.csv").read_bytes()
    stopped = dest / "mc/rnd/seed=101"
    assert (stopped / "metrics.csv").is_file() and not (stopped / "summary.json").exists()
    assert not (stopped / "checkpoint.pt").exists()


def test_a_run_held_by_a_live_process_is_never_copied(src: Path, tmp_path: Path) -> None:
    with holding_lock(src / "mc/rnd/seed=101"):
        p = land(src, tmp_path / "dest", unfinished=True)
    assert p.running == [Path("mc/rnd/seed=101")] and p.unfinished == []
    assert not (tmp_path / "dest/mc/rnd/seed=101").exists()
    assert report(p, unfinished=True, dry_run=False).splitlines() == [
        "landed 1 finished run(s) and 0 unfinished; 0 already there; 1 unfinished left in SRC (1 held by a live process)",
        "  land: mc/rnd/seed=100",
        "  left: mc/rnd/seed=101 (held by a live process)",
    ]


@pytest.mark.parametrize("finished", [True, False])
def test_dest_further_along_than_src_is_kept(src: Path, tmp_path: Path, finished: bool) -> None:
    """DEST holds the run finished, or stopped later than SRC's copy (SRC restarted it on a new machine)."""
    dest = tmp_path / "dest"
    make_run(dest, "mc/rnd/seed=101", config="seed: 101\n", steps=9, finished=finished)
    before = snapshot(dest)
    p = land(src, dest, unfinished=True)
    assert p.ahead == [Path("mc/rnd/seed=101")] and p.unfinished == []
    assert {k: v for k, v in snapshot(dest).items() if "seed=101" in k} == before
    make_run(tmp_path / "short", "mc/rnd/seed=101", config="seed: 101\n", steps=3, finished=False)
    assert land(src, tmp_path / "short", unfinished=True).unfinished == [Path("mc/rnd/seed=101")]  # SRC further


@pytest.mark.parametrize(
    "conflict",
    [
        ("mc/rnd/seed=100", {"finished": True, "steps": 7}, "another finished run"),  # another result at that path
        ("mc/rnd/seed=100", {"config": "seed: 2\n", "finished": False}, ".hydra/config.yaml differs"),
        ("mc/rnd/seed=101", {"config": "seed: 3\n", "finished": False}, ".hydra/config.yaml differs"),
    ],
)
def test_a_conflict_is_one_line_and_nothing_is_written(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], conflict: tuple[str, dict, str]
) -> None:
    dest = tmp_path / "dest"
    rel, kwargs, why = conflict
    make_run(dest, rel, **kwargs)
    before = snapshot(dest)
    with pytest.raises(SystemExit) as e:
        main([str(src), str(dest), "--unfinished"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1 and err.startswith("error: DEST ") and why in err
    assert rel in err and "allowed:" in err
    assert snapshot(dest) == before  # the other, landable runs were not copied either


@pytest.mark.parametrize(
    "args, why",
    [
        (["missing", "dest"], "SRC missing: no such directory"),
        (["wt/results/table2", "wt/results/table2/sub"], "the same as SRC"),
        (["wt/results/table2/mc", "wt/results/table2"], "the same as SRC"),
        (["empty", "dest"], "holds no run"),
    ],
)
def test_bad_directories_are_refused(
    src: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], args, why
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "empty").mkdir()
    before = snapshot(tmp_path)
    with pytest.raises(SystemExit) as e:
        main(args)
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1 and why in err
    assert snapshot(tmp_path) == before


def test_dry_run_writes_nothing_and_the_command_prints_what_it_did(
    src: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dest = tmp_path / "dest"
    main([str(src), str(dest), "--dry-run"])
    assert not dest.exists()
    assert capsys.readouterr().out.splitlines() == [
        "would land 1 finished run(s); 0 already there; 1 unfinished left in SRC (0 held by a live process)",
        "  land: mc/rnd/seed=100",
        "  left: mc/rnd/seed=101",
    ]
    main([str(src), str(dest)])
    assert capsys.readouterr().out.startswith("landed 1 finished run(s); 0 already there;")
    assert (dest / "mc/rnd/seed=100/summary.json").is_file()


def test_a_copy_that_fails_leaves_no_half_run(src: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A copy that fails half-way (a full disk) leaves DEST as it was: no half-copied directory that the analysis
    would read as a run."""
    import runners.land as land_module

    dest = tmp_path / "dest"
    make_run(dest, "mc/rnd/seed=100", finished=False, steps=2)
    before = snapshot(dest)

    def full_disk(*args: object, **kwargs: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(land_module.shutil, "copy2", full_disk)
    with pytest.raises(OSError):
        land(src, dest)
    assert snapshot(dest) == before
    assert sorted(p.name for p in (dest / "mc/rnd").iterdir()) == ["seed=100"]

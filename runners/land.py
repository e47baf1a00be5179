"""Land runs made in another clone: ``python -m runners.land SRC DEST [--unfinished] [--dry-run]``.

Long sweeps run from a separate clone or worktree of a fixed commit (so that edits do not change running jobs), into
that clone's ``results/<preset>``. This copies the finished runs below SRC into DEST (the repository's
``results/<preset>``) at the same relative paths, with only the files results keep (:data:`KEPT`: ``.hydra/``,
``metrics.csv``, ``summary.json``, ``train.log``), never TensorBoard's ``tb/`` (its scalars are ``metrics.csv``'s),
checkpoints, locks or temporary files.
A finished run is one whose directory holds ``summary.json``.

Per run, DEST may hold: nothing (the run is copied); the same finished run (the same ``summary.json`` and
``metrics.csv``: left as it is, since a re-launched sweep appends "already complete" to the source's ``train.log``);
or an unfinished copy of the same run (the same ``.hydra/config.yaml``, no ``summary.json``: a stopped run committed
earlier, replaced by its finished files). Anything else, a different run at the same path, is refused in one line
before anything is written, as are a SRC that is missing or holds no run and directories that contain each other.
Sweep-level files (Hydra's ``multirun.yaml``) are not copied: a preset is often several launches, each of which
rewrites it, while every run's ``.hydra/`` holds its own config and overrides.

``--unfinished`` also copies the unfinished runs that no live process holds (a stopped run, so that the tables list
it as incomplete instead of leaving its seed out), without their checkpoints, and never over a copy in DEST that is
further along (finished, or stopped at a later step: SRC restarted it on a new machine); they resume only where their
checkpoint is, in SRC. ``--dry-run`` says what would be done and writes nothing.
"""

from __future__ import annotations

import argparse
import filecmp
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from analysis.collect import all_run_dirs, last_step
from curiosity.runtime.checkpoint import lock_holder

KEPT = (".hydra", "metrics.csv", "summary.json", "train.log")
SAME_RUN = ("summary.json", "metrics.csv")  # equal bytes: the run DEST holds is this one


class LandError(ValueError):
    """A landing that would change or lose something DEST holds, or a source that is not a sweep's results."""


@dataclass(frozen=True)
class Plan:
    """What landing SRC into DEST does, run by run (paths relative to SRC and DEST)."""

    copy: list[Path]  # finished runs DEST lacks
    complete: list[Path]  # finished runs DEST holds an unfinished copy of (replaced)
    same: list[Path]  # finished runs DEST already holds
    unfinished: list[Path]  # unfinished runs no live process holds (copied with --unfinished)
    running: list[Path]  # unfinished runs a live process holds (never copied)
    ahead: list[Path]  # unfinished runs DEST holds finished or further along (never copied)


def run_dirs(root: Path) -> list[Path]:
    """Every run directory below ``root`` that holds ``.hydra/config.yaml``, relative to it, sorted."""
    return [d.relative_to(root) for d in all_run_dirs(root) if (d / ".hydra/config.yaml").is_file()]


def _steps(run: Path) -> int:
    step = last_step(run)
    return -1 if step is None else step


def _same_files(a: Path, b: Path, names: tuple[str, ...]) -> bool:
    return all((a / n).is_file() and (b / n).is_file() and filecmp.cmp(a / n, b / n, shallow=False) for n in names)


def plan(src: Path, dest: Path) -> Plan:
    """What landing ``src`` into ``dest`` would do; writes nothing.

    Raises:
        LandError: ``src`` missing or without runs, directories inside each other, or a run ``dest`` holds that is
            not the source's (another configuration, or another finished run at the same path).
    """
    if not src.is_dir():
        raise LandError(f"SRC {src}: no such directory; allowed: a results directory where a sweep ran")
    s, d = src.resolve(), dest.resolve()
    if s == d or s in d.parents or d in s.parents:
        raise LandError(f"DEST {dest}: the same as SRC {src} or inside it (or SRC inside DEST); allowed: the results "
                        "directory of another clone")  # fmt: skip
    if dest.exists() and not dest.is_dir():
        raise LandError(f"DEST {dest}: is a file; allowed: a directory, or a path to create one")
    runs = run_dirs(src)
    if not runs:
        raise LandError(f"SRC {src}: holds no run (no directory with .hydra/config.yaml below it); allowed: a results "
                        "directory where a sweep ran")  # fmt: skip
    out = Plan([], [], [], [], [], [])
    for rel in runs:
        a, b = src / rel, dest / rel
        if not (a / "summary.json").is_file():
            if b.exists() and any(b.iterdir()) and not _same_files(a, b, (".hydra/config.yaml",)):
                raise LandError(f"DEST {b}: holds another run than SRC's unfinished {a} (.hydra/config.yaml differs); "
                                "allowed: the same run, or no run at that path")  # fmt: skip
            if (b / "summary.json").is_file() or _steps(b) > _steps(a):
                out.ahead.append(rel)  # DEST holds more of it (finished, or a longer stopped part): never replaced
            else:
                (out.running if lock_holder(a) is not None else out.unfinished).append(rel)
            continue
        if not b.exists() or not any(b.iterdir()):
            out.copy.append(rel)
        elif (b / "summary.json").is_file():
            if not _same_files(a, b, SAME_RUN):
                raise LandError(f"DEST {b}: holds another finished run (summary.json or metrics.csv differs from "
                                f"{a}); allowed: the same run, an unfinished copy of it, or no run at that path")  # fmt: skip
            out.same.append(rel)
        elif _same_files(a, b, (".hydra/config.yaml",)):
            out.complete.append(rel)
        else:
            raise LandError(f"DEST {b}: holds another run than {a} (.hydra/config.yaml differs); allowed: the same "
                            "run, an unfinished copy of it, or no run at that path")  # fmt: skip
    return out


def copy_run(src_run: Path, dest_run: Path) -> None:
    """Copy the kept files of one run into ``dest_run`` (replacing what it holds), through a sibling temporary
    directory and a rename, so that an interrupted copy leaves DEST's earlier files in place."""
    dest_run.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest_run.name}.", suffix=".landing", dir=dest_run.parent))
    try:
        for name in KEPT:
            p = src_run / name
            if p.is_dir():
                shutil.copytree(p, tmp / name)
            elif p.is_file():
                shutil.copy2(p, tmp / name)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)  # a half copy would read as a run of its own
        raise
    old = None
    if dest_run.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{dest_run.name}.", suffix=".replaced", dir=dest_run.parent))
        old.rmdir()
        dest_run.rename(old)
    tmp.rename(dest_run)
    if old is not None:
        shutil.rmtree(old)


def land(src: Path, dest: Path, unfinished: bool = False, dry_run: bool = False) -> Plan:
    """Carry out :func:`plan` (unless ``dry_run``); returns it."""
    p = plan(src, dest)
    if dry_run:
        return p
    for rel in p.copy + p.complete + (p.unfinished if unfinished else []):
        copy_run(src / rel, dest / rel)
    return p


def report(p: Plan, unfinished: bool, dry_run: bool) -> str:
    """One summary line, then one line per run landed (``land:``) and per unfinished run left in SRC (``left:``)."""
    verb = "would land" if dry_run else "landed"
    lines = [f"  land: {rel}" for rel in p.copy] + [f"  land: {rel} (completes its unfinished copy)" for rel in p.complete]
    if unfinished:
        lines += [f"  land: {rel} (unfinished)" for rel in p.unfinished]
    head = (f"{verb} {len(p.copy) + len(p.complete)} finished run(s)"
            + (f" and {len(p.unfinished)} unfinished" if unfinished else "")
            + f"; {len(p.same)} already there")  # fmt: skip
    left = ([] if unfinished else p.unfinished) + p.running
    if left:
        head += f"; {len(left)} unfinished left in SRC ({len(p.running)} held by a live process)"
        lines += [f"  left: {rel}" + (" (held by a live process)" if rel in p.running else "") for rel in left]
    if p.ahead:
        head += f"; {len(p.ahead)} unfinished in SRC that DEST holds further along"
    return "\n".join([head, *lines])


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src", type=Path, help="the results directory of the clone where the runs ran, e.g. "
                    "../wt/results/table2")  # fmt: skip
    ap.add_argument("dest", type=Path, help="this repository's results directory of the same preset, e.g. results/table2")
    ap.add_argument("--unfinished", action="store_true", help="also copy unfinished runs no live process holds")
    ap.add_argument("--dry-run", action="store_true", help="say what would be done; write nothing")
    args = ap.parse_args(argv)
    try:
        p = land(args.src, args.dest, args.unfinished, args.dry_run)
    except LandError as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(2) from None
    print(report(p, args.unfinished, args.dry_run))


if __name__ == "__main__":
    main()

"""The logger façade: one call feeds the CSV and TensorBoard; undeclared keys are refused."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from curiosity.runtime.logger import RunLogger


def test_record_dump_averages_and_writes_both(tmp_path: Path) -> None:
    log = RunLogger(tmp_path, ["losses/a", "charts/b"])
    log.record("losses/a", 1.0)
    log.record("losses/a", 2.0)
    log.dump(10)
    log.record("charts/b", 0.25)
    log.dump(20)
    # flushed as it goes: readable before close
    with (tmp_path / "metrics.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert rows == [{"step": "10", "losses/a": "1.5", "charts/b": ""}, {"step": "20", "losses/a": "", "charts/b": "0.25"}]
    log.close()
    acc = EventAccumulator(str(tmp_path / "tb"))
    acc.Reload()
    assert [(e.step, e.value) for e in acc.Scalars("losses/a")] == [(10, 1.5)]
    assert [(e.step, e.value) for e in acc.Scalars("charts/b")] == [(20, 0.25)]


def test_undeclared_key_is_an_error(tmp_path: Path) -> None:
    log = RunLogger(tmp_path, ["losses/a"])
    with pytest.raises(KeyError, match="losses/typo"):
        log.record("losses/typo", 1.0)
    log.close()

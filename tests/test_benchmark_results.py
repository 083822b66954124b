"""Benchmarks write their results to ``benchmarks/results/<name>.md`` (benchmarks/recording.py)."""
from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def _recording():
    spec = importlib.util.spec_from_file_location("recording", BENCHMARKS / "recording.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_completed_run_is_written_with_its_header(tmp_path, capsys):
    recording = _recording()
    with recording.recorded("demo", ["--cases", "3"], tmp_path):
        print("pass rate: 3/3")
        print("median 1.7 s")
    assert capsys.readouterr().out == "pass rate: 3/3\nmedian 1.7 s\n"
    text = (tmp_path / "demo.md").read_text()
    assert text.startswith("# Benchmark `demo`\n")
    assert "- run: `python benchmarks/demo.py --cases 3`" in text
    assert re.search(r"- finished: \d{4}-\d\d-\d\d \d\d:\d\d UTC", text)
    assert re.search(r"- code: ([0-9a-f]{4,}|unknown)", text)
    assert text.endswith("```text\npass rate: 3/3\nmedian 1.7 s\n```\n")


def test_a_failed_run_keeps_the_previous_results(tmp_path):
    recording = _recording()
    (tmp_path / "demo.md").write_text("previous\n")
    with pytest.raises(RuntimeError):
        with recording.recorded("demo", [], tmp_path):
            print("half a table")
            raise RuntimeError("interrupted")
    assert (tmp_path / "demo.md").read_text() == "previous\n"


def test_every_benchmark_records_its_results():
    """Each script runs its main inside ``recorded`` under its own name; no run logs in docstrings."""
    for script in sorted(BENCHMARKS.glob("*.py")):
        if script.name == "recording.py":
            continue
        source = script.read_text()
        assert re.search(rf'recorded\("{script.stem}"[,)]', source), script.name
        assert not re.search(r"(?i)last run|before \(pfmdyn at|measured on this machine", source), script.name

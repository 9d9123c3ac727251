"""scripts/trace_corpus.py: every file of a folder through ``cnc-gym trace``, one line each, counts at the
end (the measurement of a corpus of real programs before and after a change)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "trace_corpus.py"


def _script():
    spec = importlib.util.spec_from_file_location("trace_corpus", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_each_file_is_traced_or_refused_with_its_code(tmp_path, capsys):
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    (corpus / "a_plain.nc").write_text("G00 X1.\nG01 Y2. F100.\nM30\n")
    (corpus / "b_machine_code.nc").write_text("M20\nG00 X1.\n")  # traced, with a note
    (corpus / "c_grbl.gcode").write_text("G01 X10 F100 ; a grbl comment\n")
    out = tmp_path / "out.jsonl"
    assert _script().main([str(corpus), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert [(r["file"], r["outcome"], r["code"], r["motions"]) for r in records] == [
        ("a_plain.nc", "traced", "", 2), ("b_machine_code.nc", "traced", "", 2),
        ("c_grbl.gcode", "refused", "missing-value", 0)]  # fmt: skip
    assert "machine-function" in records[1]["message"]
    assert "3 files: 2 traced, 1 refused, 0 crashed" in text and "refused by code: missing-value 1" in text


def test_options_after_a_double_dash_go_to_trace(tmp_path, capsys):
    corpus = tmp_path / "corpus"
    corpus.mkdir()
    (corpus / "rotary.nc").write_text("G00 X1. A90.\nM30\n")
    script = _script()
    assert script.main([str(corpus), "--timeout", "60"]) == 0
    assert "refused  unsupported-axis" in capsys.readouterr().out
    assert script.main([str(corpus), "--timeout", "60", "--", "--machine", "vmc-4axis"]) == 0
    assert "1 files: 1 traced, 0 refused" in capsys.readouterr().out

"""The `cnc-gym` command: the trace contract and the error contract (docs/architecture.md)."""

from __future__ import annotations

import json
import subprocess
import sys
import types
from pathlib import Path

import pytest

from cnc_gym.cli import main

CONTRACT_KEYS = {
    "rapid": {"kind", "line", "end"},
    "line": {"kind", "line", "end", "feed"},
    "arc": {"kind", "line", "end", "feed", "center", "plane", "sweep_deg"},
    "dwell": {"kind", "line", "seconds"},
}


def write(tmp_path: Path, text: str, name: str = "part.nc") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def run_main(argv: list[str], capsys) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_trace_prints_json_lines_per_the_contract(tmp_path, capsys):
    text = "G00 X10 Y5\nG01 Z-1 F200\nG02 X20 Y5 I5 F400\nG04 P250\nG18 G03 X30 Z-1 R5\nM30\n"
    program = write(tmp_path, text)
    code, out, err = run_main(["trace", program], capsys)
    assert code == 0 and err == ""
    recs = [json.loads(line) for line in out.splitlines()]
    assert [r["kind"] for r in recs] == ["rapid", "line", "arc", "dwell", "arc"]
    assert [r["line"] for r in recs] == [1, 2, 3, 4, 5]
    for rec in recs:
        assert CONTRACT_KEYS[rec["kind"]] <= set(rec)
    # Values: a half circle CW about (15, 5) from (10, 5) to (20, 5) at F400; G04 P250 = 0.25 s.
    assert recs[2]["center"] == [15.0, 5.0, -1.0] and recs[2]["sweep_deg"] == -180.0
    assert recs[2]["feed"] == 400.0
    assert recs[3]["seconds"] == 0.25
    assert recs[4]["plane"] == "ZX" and recs[4]["end"] == [30.0, 5.0, -1.0]


def test_trace_block_skip_switches(tmp_path, capsys):
    program = write(tmp_path, "G00 X1\n/G00 X2\n/2 G00 X3\n")
    _, out_off, _ = run_main(["trace", program], capsys)
    _, out_on, _ = run_main(["trace", program, "--block-skip", "1", "2"], capsys)
    assert len(out_off.splitlines()) == 3 and len(out_on.splitlines()) == 1


@pytest.mark.parametrize(
    ("text", "line", "code"),
    [
        ("G00 X1\nG01 X1.2.3 F100\n", 2, "bad-number"),
        ("G00 X1\nG01 X F100\n", 2, "missing-value"),
        ("G00 X1\nG12 X1\n", 2, "unknown-code"),
        ("G00 X1\nG43.4 H1\n", 2, "not-implemented"),  # (G41 is implemented now: compensation.py)
        ("G00 X1\nG02 X30 R10 F100\n", 2, "arc-impossible"),
        ("G00 X10\nG03 X0 Y10.5 I-10 F100\n", 2, "arc-radius-mismatch"),
        ("G00 X1\n\nG01 X2\n", 3, "missing-feed"),
        ("G00 X1\nG00 G01 X2 F100\n", 2, "group-conflict"),
        ("G00 X1\nG00 X[1/0]\n", 2, "division-by-zero"),
    ],
)
def test_program_errors_exit_2_with_one_line_and_no_stdout(tmp_path, capsys, text, line, code):
    program = write(tmp_path, text)
    status, out, err = run_main(["trace", program], capsys)
    assert status == 2
    assert out == ""  # nothing on stdout, not even the records before the error
    lines = err.splitlines()
    assert len(lines) == 1
    assert lines[0].startswith(f"{program}:{line}: ") and lines[0].endswith(f"[{code}]")


def test_missing_and_unreadable_files(tmp_path, capsys):
    status, out, err = run_main(["trace", str(tmp_path / "nope.nc")], capsys)
    assert status == 2 and out == "" and len(err.splitlines()) == 1 and "nope.nc" in err
    status, out, err = run_main(["trace", str(tmp_path)], capsys)  # a directory
    assert status == 2 and out == "" and len(err.splitlines()) == 1


def test_byte_order_mark_and_latin1_files(tmp_path, capsys):
    bom = tmp_path / "bom.nc"
    bom.write_bytes(b"\xef\xbb\xbfG00 X1\n")
    latin = tmp_path / "latin.nc"
    latin.write_bytes(b"(Werkst\xfcck)\nG00 X2\n")
    for path, x in ((bom, 1.0), (latin, 2.0)):
        status, out, err = run_main(["trace", str(path)], capsys)
        assert status == 0 and err == "" and json.loads(out)["end"][0] == x


def test_bad_dialect_and_machine_are_one_line_errors(tmp_path, capsys):
    program = write(tmp_path, "G00 X1\n")
    for argv in (["--dialect", "nonsense"], ["--machine", "no-such-machine"]):
        status, out, err = run_main(["trace", program, *argv], capsys)
        assert status == 2 and out == "" and len(err.splitlines()) == 1, argv


def test_machine_travel_limits_are_checked(tmp_path, capsys):
    machine = tmp_path / "tiny.yaml"
    machine.write_text("name: tiny\naxis_defaults: {min_position_mm: -100, max_position_mm: 100}\n")
    program = write(tmp_path, "G00 X50\nG00 X150\n")
    status, out, err = run_main(["trace", program, "--machine", str(machine)], capsys)
    assert status == 2 and out == "" and err.startswith(f"{program}:2: ") and "[travel-limit]" in err
    # A circle whose ends are inside but whose far side is not: centre (60, 0), radius 50 reaches X 110.
    circle = write(tmp_path, "G00 X10\nG01 Z0 F100\nG02 I50\n", "circle.nc")
    status, out, err = run_main(["trace", circle, "--machine", str(machine)], capsys)
    assert status == 2 and out == "" and err.startswith(f"{circle}:3: OVER TRAVEL:+1: X110.0000")
    # ... a CW quarter arc from 180° to 90° about (60, 0) stays inside (the CCW way round would not).
    inside_arc = write(tmp_path, "G00 X10\nG02 X60 Y50 I50 F100\n", "arc.nc")
    assert run_main(["trace", inside_arc, "--machine", str(machine)], capsys)[0] == 0
    outside_arc = write(tmp_path, "G00 X10\nG03 X60 Y50 I50 F100\n", "arc3.nc")
    status, _, err = run_main(["trace", outside_arc, "--machine", str(machine)], capsys)
    assert status == 2 and "X110.0000" in err
    inside = write(tmp_path, "G00 X50\n", "ok.nc")
    status, out, _ = run_main(["trace", inside, "--machine", str(machine)], capsys)
    assert status == 0 and out


def _stub_runner(monkeypatch) -> dict:
    """Replace the runner with one that records the parsed arguments (returned, filled when it runs)."""
    seen: dict = {}

    def run_cli(args):
        seen.update(vars(args))
        return 0

    monkeypatch.setitem(sys.modules, "cnc_gym.runner", types.SimpleNamespace(run_cli=run_cli))
    return seen


def test_run_dispatches_to_the_runner(tmp_path, capsys, monkeypatch):
    seen = _stub_runner(monkeypatch)
    program = write(tmp_path, "G00 X1\n")
    assert main(["run", program, "--json", "--plot", "p.png", "--no-progress"]) == 0
    assert seen["program"] == program and seen["policy"] == "constant:1.0" and seen["json"] is True
    assert seen["plot"] == "p.png" and seen["no_progress"] is True and seen["dialect"] == "gsk25i"
    assert seen["units"] is None
    assert main(["run", program, "--units", "inch"]) == 0 and seen["units"] == "inch"


SETUP_FILE = "work_offsets:\n  G54: [100.0, 50.0, -200.0]\ntools:\n  1: {length_mm: 120.0, radius_mm: 5.0}\n"


def test_trace_setup_gives_the_work_and_tool_offsets(tmp_path, capsys):
    # G54 = (100, 50, -200), H1 = 120: Z10 with G43 H1 is machine -70. A preset's setup section is below
    # the file's; a bad file is one line, exit 2, nothing on stdout.
    program = write(tmp_path, "G54 G00 X0 Y0\nG43 H1 Z10.\n")
    setup = write(tmp_path, SETUP_FILE, "job.yaml")
    status, out, err = run_main(["trace", program, "--dialect", "fanuc", "--setup", setup], capsys)
    assert status == 0 and err == ""
    ends = [json.loads(line)["end"] for line in out.splitlines()]
    assert ends == [[100.0, 50.0, 0.0], [100.0, 50.0, -70.0]]
    preset = write(tmp_path, "name: shop\nsetup:\n  work_offsets:\n    G54: [1.0, 2.0, 3.0]\n", "shop.yaml")
    status, out, _ = run_main(["trace", program, "--dialect", "fanuc", "--machine", preset], capsys)
    assert status == 0 and json.loads(out.splitlines()[0])["end"] == [1.0, 2.0, 0.0]
    status, out, _ = run_main(["trace", program, "--dialect", "fanuc", "--machine", preset, "--setup", setup],
                              capsys)  # fmt: skip
    assert status == 0 and json.loads(out.splitlines()[0])["end"] == [100.0, 50.0, 0.0]
    bad = write(tmp_path, "tools:\n  1: {length: 1}\n", "bad.yaml")
    status, out, err = run_main(["trace", program, "--setup", bad], capsys)
    assert status == 2 and out == ""
    assert err.strip().endswith("unknown key tools.1.length (allowed: length_mm, length_wear_mm, radius_mm, "
                                "radius_wear_mm)")
    ext = write(tmp_path, "work_offsets:\n  EXT: [0, 0, 0]\n", "ext.yaml")
    status, out, err = run_main(["trace", program, "--dialect", "h4cm", "--setup", ext], capsys)
    assert status == 2 and out == "" and "work_offsets.EXT cannot be set" in err
    assert len(err.splitlines()) == 1


def test_trace_calculator_input(tmp_path, capsys):
    # fanuc reads X10 as 10 least increments (0.01 mm); --calculator-input as 10 mm (parameter 3401#0 DPI
    # = 1), as a preset's calculator_input does. A dialect without the setting is one line, exit 2.
    program = write(tmp_path, "G00 X10\n")

    def end_x(*argv):
        status, out, err = run_main(["trace", program, "--dialect", "fanuc", *argv], capsys)
        assert status == 0, err
        return json.loads(out.splitlines()[0])["end"][0]

    assert end_x() == 0.01
    assert end_x("--calculator-input") == 10.0
    assert end_x("--machine", write(tmp_path, "calculator_input: true\n", "calc.yaml")) == 10.0
    status, out, err = run_main(["trace", program, "--dialect", "syntec", "--calculator-input"], capsys)
    assert status == 2 and out == "" and "no calculator-type input setting" in err


def test_run_setup_travels_in_the_machine_record(tmp_path, capsys, monkeypatch):
    seen = _stub_runner(monkeypatch)
    program = write(tmp_path, "G00 X1\n")
    assert main(["run", program, "--setup", write(tmp_path, SETUP_FILE, "job.yaml")]) == 0
    machine = seen["machine"]
    assert machine.name == "vmc-small" and machine.setup.work_offsets["G54"] == (100.0, 50.0, -200.0)
    assert machine.setup.tools[1].length_mm == 120.0 and not machine.calculator_input
    assert main(["run", program, "--calculator-input"]) == 0 and seen["machine"].calculator_input


def test_run_with_a_setup_simulates_the_offset_path(tmp_path, capsys):
    # The same program with and without the setup: the G54 offset moves the first rapid 100 mm further.
    program = write(tmp_path, "G54 G00 X0 Y0\nG01 X10. F3000.\nM30\n")
    results = {}
    for name, extra in (("plain", []), ("setup", ["--setup", write(tmp_path, SETUP_FILE, "job.yaml")])):
        status, out, _ = run_main(["run", program, "--dialect", "fanuc", "--json", "--no-progress", *extra],
                                  capsys)  # fmt: skip
        assert status == 0
        results[name] = json.loads(out)
    assert results["setup"]["nominal_time_s"] > results["plain"]["nominal_time_s"] + 0.1


def test_run_without_a_runner_is_a_one_line_error(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "cnc_gym.runner", None)  # import fails
    status, out, err = run_main(["run", write(tmp_path, "G00 X1\n")], capsys)
    assert status == 2 and out == "" and len(err.splitlines()) == 1 and "runner" in err


def test_console_command_never_prints_a_traceback(tmp_path):
    # The real entry point in a fresh interpreter: exit status 2, one stderr line, empty stdout.
    program = write(tmp_path, "G01 X10 F100\nG02 X50 R5\n")
    proc = subprocess.run([sys.executable, "-m", "cnc_gym.cli", "trace", program], capture_output=True,
                          text=True, timeout=60)  # fmt: skip
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"{program}:2: ") and proc.stderr.rstrip().endswith("[arc-impossible]")


# ------------------------------------------------------------------------------- programs and options
def test_trace_takes_built_in_names_like_run(capsys):
    from cnc_gym.programs import program_path

    status, by_name, err = run_main(["trace", "star"], capsys)
    assert status == 0 and err == ""
    _, by_file, _ = run_main(["trace", str(program_path("star"))], capsys)
    assert by_name == by_file and len(by_name.splitlines()) > 10


@pytest.mark.parametrize("command", ["trace", "run"])
def test_help_says_program_may_be_a_built_in_name_and_lists_exit_statuses(capsys, command):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "built-in program name: circle, star, freeform, pocket" in text
    assert "exit status" in text and "3 (run) truncated" in text


@pytest.mark.parametrize("text", ["G90\nM30\n", "", "T1 M06\nM03 S1000\nM05\nM30\n"])
def test_trace_of_a_program_without_motion_prints_nothing(tmp_path, capsys, text):
    status, out, err = run_main(["trace", write(tmp_path, text)], capsys)
    assert (status, out, err) == (0, "", "")


@pytest.mark.parametrize("command", ["trace", "run"])
def test_dev_null_is_an_empty_program_for_both_commands(capsys, command):
    extra = ["--no-progress"] if command == "run" else []
    status, out, err = run_main([command, "/dev/null", *extra], capsys)
    assert status == 0 and err == ""
    if command == "run":
        assert out.splitlines()[-1].split()[-1] == "yes"


@pytest.mark.parametrize(("command", "option"), [("trace", "--dialect"), ("trace", "--machine"),
                                                 ("run", "--dialect"), ("run", "--machine"),
                                                 ("run", "--policy")])  # fmt: skip
def test_empty_option_values_are_rejected_by_both_commands(tmp_path, capsys, command, option):
    extra = ["--no-progress"] if command == "run" else []
    status, out, err = run_main([command, write(tmp_path, "G00 X1\n"), f"{option}=", *extra], capsys)
    assert status == 2 and out == "" and len(err.splitlines()) == 1 and option in err


LOOP = "#1=0\nWHILE [#1 LT 50] DO1\n#1=#1+1\nEND1\nG01 X10 F100\nM30\n"  # about 150 blocks


@pytest.mark.parametrize("command", ["trace", "run"])
def test_max_blocks_is_settable_from_the_command_line(tmp_path, capsys, command):
    program = write(tmp_path, LOOP)
    extra = ["--no-progress"] if command == "run" else []
    status, out, err = run_main([command, program, "--max-blocks", "40", *extra], capsys)
    assert status == 2 and out == "" and err.rstrip().endswith("[too-many-blocks]")
    status, out, err = run_main([command, program, "--max-blocks", "100000", *extra], capsys)
    assert status == 0 and err == "" and out
    status, _, err = run_main([command, program, "--max-blocks", "0", *extra], capsys)
    assert status == 2 and "--max-blocks" in err


def test_one_line_gcode_with_a_slash_is_text_not_a_path(capsys):
    # X[10/4] is an expression, "/G00 X5" a block with its skip mark: neither is a path.
    status, out, err = run_main(["trace", "G01 X[10/4] F100"], capsys)
    assert status == 0 and err == "" and json.loads(out)["end"][0] == 2.5
    status, out, _ = run_main(["trace", "/G00 X5"], capsys)
    assert status == 0 and json.loads(out)["end"][0] == 5.0  # block skip switch off: the block runs
    status, out, _ = run_main(["trace", "/G00 X5", "--block-skip", "1"], capsys)
    assert status == 0 and out == ""
    status, out, err = run_main(["trace", "examples/no-such-part"], capsys)
    assert status == 2 and out == "" and "not a built-in" in err and "nor an existing file" in err


def test_docs_cli_matches_the_code():
    # docs/cli.md is derived from these constants; a change to one without the other fails here.
    from cnc_gym.envs.render import ALONG_PATH_BINS, DEFAULT_MAX_BINS
    from cnc_gym.gcode.settings import DEFAULT_MAX_BLOCKS
    from cnc_gym.runner import EXIT_TRUNCATED, JSON_KEYS, LONG_RUN_NOTICE_S, PATH_ERROR_BINS, PLOT_FORMATS

    text = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text(encoding="utf-8")
    for key in JSON_KEYS:
        assert f"`{key}`" in text, key
    assert f"default {DEFAULT_MAX_BLOCKS:,}" in text
    assert f"at most {DEFAULT_MAX_BINS} time bins" in text
    assert f"a max envelope of at most {ALONG_PATH_BINS}\nsteps" in text
    assert f"kept in {PATH_ERROR_BINS}\npath-length bins" in text
    assert f"exceeds {LONG_RUN_NOTICE_S / 60:g} minutes" in text
    assert f"| {EXIT_TRUNCATED} | `run` only: truncated" in text
    assert all(f"`{suffix}`" in text for suffix in PLOT_FORMATS)


def test_trace_units_and_the_machine_presets_power_on_units(tmp_path, capsys):
    # A program without G20/G21: --units inch reads X1. as 1 inch; a preset's power_on_units is the default
    # of the option; the option rules over the preset; the program's G21 rules over both.
    program = write(tmp_path, "G00 X1.\n")
    inch_machine = tmp_path / "inch.yaml"
    inch_machine.write_text("name: inch-shop\npower_on_units: inch\n")

    def end_x(*argv):
        status, out, err = run_main(["trace", *argv], capsys)
        assert status == 0 and err == "", err
        return json.loads(out.splitlines()[0])["end"][0]

    assert end_x(program) == 1.0
    assert end_x(program, "--units", "inch") == 25.4
    assert end_x(program, "--units", "mm") == 1.0
    assert end_x(program, "--machine", str(inch_machine)) == 25.4
    assert end_x(program, "--machine", str(inch_machine), "--units", "mm") == 1.0
    assert end_x(write(tmp_path, "G21 G00 X1.\n", "metric.nc"), "--units", "inch") == 1.0
    assert end_x(program, "--dialect", "fanuc", "--units", "inch") == 25.4


def test_units_option_errors(tmp_path, capsys):
    program = write(tmp_path, "G00 X1.\n")
    with pytest.raises(SystemExit) as exit_:
        main(["trace", program, "--units", "cm"])
    assert exit_.value.code == 2 and "invalid choice: 'cm'" in capsys.readouterr().err
    bad = tmp_path / "bad.yaml"
    bad.write_text("power_on_units: metric\n")
    status, out, err = run_main(["trace", program, "--machine", str(bad)], capsys)
    assert status == 2 and out == "" and "power_on_units" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize(("argv", "fragment"), [
    (["bench", "--workers", "x"], "cnc-gym bench: error: argument --workers: invalid int value: 'x'"),
    (["bench", "--bogus", "1"], "cnc-gym bench: error: unrecognized arguments: --bogus 1"),
    (["run"], "cnc-gym run: error: the following arguments are required: PROGRAM"),
    (["trace", "star", "--block-skip", "a"], "cnc-gym trace: error: argument --block-skip"),
    (["frob"], "cnc-gym: error: argument COMMAND: invalid choice: 'frob'"),
    ([], "cnc-gym: error: the following arguments are required: COMMAND"),
])  # fmt: skip
def test_usage_errors_are_the_usage_line_and_one_error_line(argv, fragment, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert exit_.value.code == 2 and out == "" and len(lines) == 2, err
    command = "cnc-gym " + argv[0] if argv and argv[0] in ("bench", "run", "trace") else "cnc-gym"
    assert lines[0].startswith(f"usage: {command} ") and lines[0].endswith(f"(all of them: {command} --help)")
    assert lines[1].startswith(fragment), lines[1]


def test_help_still_shows_the_whole_usage(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["bench", "--help"])
    assert exit_.value.code == 0 and "--per-family N" in capsys.readouterr().out


def test_docs_state_the_defaults_the_code_names():
    # The defaults live once, as DEFAULT_DIALECT (cnc_gym/gcode/dialect.py) and DEFAULT_MACHINE
    # (cnc_gym/machine.py); docs/cli.md's option table states them.
    from cnc_gym.cli import DIALECTS
    from cnc_gym.gcode.dialect import DEFAULT_DIALECT, DIALECT_MODULES
    from cnc_gym.machine import DEFAULT_MACHINE, machine_names

    rows = {line.split("|")[1].strip(): line for line in
            (Path(__file__).resolve().parent.parent / "docs" / "cli.md").read_text().splitlines()
            if line.startswith("| `--")}  # fmt: skip
    assert f"`{DEFAULT_DIALECT}` (default)" in rows["`--dialect D`"]
    assert f"`run` defaults to `{DEFAULT_MACHINE}`" in rows["`--machine M`"]
    assert DEFAULT_MACHINE in machine_names()
    assert DEFAULT_DIALECT in DIALECT_MODULES and tuple(DIALECT_MODULES) == DIALECTS

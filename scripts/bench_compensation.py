"""Cost of cutter radius compensation: the same 20 000-block contour (lines and arcs) interpreted with and
without G41. Prints CPU time (best of 3) and blocks per second.

    .venv/bin/python scripts/bench_compensation.py
"""

from __future__ import annotations

import time

from cnc_gym.gcode import interpret

BLOCKS = 20_000


def contour(compensated: bool) -> str:
    lines = ["G10 L12 P1 R1", "G00 X-10 Y0", f"G01 {'G41 D1 ' if compensated else ''}X0 Y0 F1000"]
    for i in range(BLOCKS):
        if i % 4 == 3:
            lines.append(f"G03 X{(i + 1) * 5:.4f} Y0 R2.5")
        else:
            lines.append(f"G01 X{(i + 1) * 5:.4f} Y{3 if i % 2 else 0}")
    lines.append(f"G01 G40 X{BLOCKS * 5 + 10:.4f} Y-10")
    return "\n".join(lines) + "\n"


def main() -> None:
    for name, compensated in (("without G41", False), ("with G41   ", True)):
        text = contour(compensated)
        best = float("inf")
        for _ in range(3):
            start = time.process_time()
            toolpath = interpret(text)
            best = min(best, time.process_time() - start)
        print(f"{name}: {len(toolpath)} segments, {best * 1000:.0f} ms CPU, {BLOCKS / best:,.0f} blocks/s")


if __name__ == "__main__":
    main()

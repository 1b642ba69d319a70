"""Blender's drape and tailor's, alternated pair by pair, with the ratio of each pair.

The host's speed changes by the hour (by 40% on a shared 2-core machine), so a ratio means
something only between runs made one right after the other. Each pair runs Blender's drape
(`bench/blender_drape.py`, self-collision on) and then `tailor simulate` on the same drape,
and prints Blender's time for its 60 simulated frames, tailor's wall time for the whole
process (every frame simulated, checked and written), their ratio, and what each run's
quality was: Blender's worst stretch, tailor's worst strain and its frames not clean (a
point of the written surface within the thickness of the sphere, or a self-intersection).
A tailor run that fails, or whose frames are not all clean, stops the comparison.

    cargo run --release --example drape_scene -- 64 1 drape64
    python3 bench/drape_ratio.py --blender-python /path/to/bpy/python \
        target/release/tailor drape64/drape.toml 64 [--pairs 4]

`--blender-python` is a Python with the `bpy` module (`pip install "bpy==4.5.*"` in Python
3.11); `--blender BIN` runs a Blender executable in the background instead.
"""

import argparse
import json
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SCRIPT = HERE / "blender_drape.py"
BLENDER_LINE = re.compile(r"([\d.]+) ms/frame, worst stretch ([\d.]+)%")
SIMULATED_FRAMES = 60


def blender_command(args):
    drape = ["--", str(args.n), "--self"]
    if args.blender:
        return [args.blender, "-b", "--factory-startup", "--python", str(SCRIPT), *drape]
    return [args.blender_python, str(SCRIPT), *drape]


def run_blender(args):
    """Blender's seconds for the simulated frames, and its worst stretch in percent."""
    out = subprocess.run(blender_command(args), capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"Blender failed (exit {out.returncode}):\n{out.stderr}")
    found = BLENDER_LINE.search(out.stdout)
    if found is None:
        sys.exit(f"no timing in Blender's output:\n{out.stdout}\n{out.stderr}")
    return float(found[1]) * SIMULATED_FRAMES / 1000.0, float(found[2])


def run_tailor(args):
    """tailor's wall seconds for the whole process, its worst strain in percent, and the
    frames that were not clean."""
    start = time.perf_counter()
    out = subprocess.run(
        [args.tailor, "simulate", args.scene, "-q"], capture_output=True, text=True
    )
    seconds = time.perf_counter() - start
    if out.returncode != 0:
        sys.exit(f"tailor failed (exit {out.returncode}):\n{out.stderr}")
    summary = re.search(r"^summary: (.+)$", out.stdout, re.MULTILINE)
    if summary is None:
        sys.exit(f"no summary in tailor's output:\n{out.stdout}")
    total = json.loads(Path(summary[1]).read_text())["total"]
    return seconds, 100.0 * total["max_strain"], total["frames_not_clean"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tailor", help="the tailor executable")
    parser.add_argument("scene", help="the drape's scene (examples/drape_scene writes it)")
    parser.add_argument("n", type=int, help="vertices a side of the scene's sheet")
    parser.add_argument("--pairs", type=int, default=4)
    parser.add_argument(
        "--pause",
        type=float,
        default=2.0,
        help="seconds to wait before each run, for the system to settle after the last",
    )
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--blender-python", default=sys.executable)
    which.add_argument("--blender", help="a Blender executable, run with -b")
    args = parser.parse_args()

    ratios = []
    for pair in range(1, args.pairs + 1):
        time.sleep(args.pause)
        blender, stretch = run_blender(args)
        time.sleep(args.pause)
        tailor, strain, not_clean = run_tailor(args)
        ratios.append(blender / tailor)
        print(
            f"pair {pair}: Blender {blender:.2f} s (stretch {stretch:.1f}%), "
            f"tailor {tailor:.2f} s (strain {strain:.1f}%, {not_clean} frames not clean): "
            f"{ratios[-1]:.1f}x",
            flush=True,
        )
        if not_clean:
            sys.exit("tailor's written frames are not all clean")
    print(
        f"{args.n}², {args.pairs} pairs: Blender ÷ tailor {min(ratios):.1f}–{max(ratios):.1f}x, "
        f"median {statistics.median(ratios):.1f}x"
    )


if __name__ == "__main__":
    main()

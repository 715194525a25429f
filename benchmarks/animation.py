"""Time to write an animation of a run (``gyrolab --plot --animate``), per frame and in all.

    python benchmarks/animation.py                    # 120 frames (the default), GIF
    python benchmarks/animation.py --frames 30 60 120 --format gif

Integrates the default scene over t ∈ [0, 6] once (2 c-units of spin), then times ``animate`` for each frame
count (CPU seconds of this process, ``time.process_time``, so other work on a shared machine inflates them less
than wall time) and reports the file size. The drawing is matplotlib's: about the cost of redrawing one 3-D
figure per frame at 100 dpi.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, nargs="+", default=[120])
    parser.add_argument("--format", default="gif", choices=("gif", "mp4"))
    args = parser.parse_args()

    from gyrolab import run
    from gyrolab.figures.animation import animate
    from gyrolab.output.dataset import write_dataset

    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        write_dataset(run(["time.end=6", "initial.r0=2", "output.figures=false"]), directory / "run.nc")
        animate(directory, output=directory / f"warm.{args.format}", fmt=args.format, frames=2)  # imports, fonts
        print(f"{'frames':>6} {'CPU s':>7} {'ms/frame':>9} {'size kB':>8}")
        for frames in args.frames:
            start = time.process_time()
            path = animate(directory, output=directory / f"a{frames}.{args.format}", fmt=args.format, frames=frames)
            cpu = time.process_time() - start
            print(f"{frames:>6} {cpu:>7.2f} {1000 * cpu / frames:>9.1f} {path.stat().st_size / 1024:>8.0f}")


if __name__ == "__main__":
    main()

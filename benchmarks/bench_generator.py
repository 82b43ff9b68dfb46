"""Speed and FS-rule results of the random track generator (issue 15: <= 1 s a track).

For each size, generates tracks for seeds 5000-5049 (seeds the tests do not
use) and prints the CPU time per track (``time.process_time``, so other work
on a shared machine does not count: median, 95th percentile, max), the
lap length range and the FS findings of
``track check`` on the result: how many tracks have warnings or errors,
the narrowest derived width and the tightest turn (lane-centre radius, the
curvature averaged over 2 m as ``track check`` averages it). Deriving the
geometry is not part of generating. Run: ``python benchmarks/bench_generator.py``.
"""

from __future__ import annotations

import statistics
import time
from collections import Counter

import numpy as np
from scipy.ndimage import uniform_filter1d

from conesim.tracks import TrackSpec, check_report, generate_track
from conesim.tracks.generate.spec import SIZE_LENGTHS

SEEDS = range(5000, 5050)


def main() -> None:
    """Print one block per size."""
    print(f"{len(SEEDS)} seeds per size ({SEEDS.start}-{SEEDS.stop - 1}); CPU time per track")
    print(
        f"{'size':<8}{'median':>9}{'p95':>8}{'max':>8}{'lap [m]':>14}"
        f"{'warned':>8}{'errors':>8}{'min width':>11}{'min R':>8}"
    )
    for size in SIZE_LENGTHS:
        spec = TrackSpec(size=size)  # type: ignore[arg-type]
        times, lengths, widths, radii = [], [], [], []
        warned = errors = 0
        findings: Counter[str] = Counter()
        for seed in SEEDS:
            t0 = time.process_time()
            track = generate_track(seed, spec)
            times.append(time.process_time() - t0)
            report = check_report(track)
            lengths.append(track.length_m)
            widths.append(float(track.widths.min()))
            kappa = np.abs(uniform_filter1d(track.geometry.curvature, 4, mode="wrap"))
            radii.append(float(1.0 / kappa.max()))
            warned += bool(report["warnings"])
            errors += bool(report["errors"])
            findings.update(w.split(" m ")[0] for w in report["warnings"])
        p95 = float(np.percentile(times, 95))
        print(
            f"{size:<8}{statistics.median(times):>8.3f}s{p95:>7.3f}s{max(times):>7.3f}s"
            f"{min(lengths):>7.0f}-{max(lengths):<6.0f}{warned:>8d}{errors:>8d}"
            f"{min(widths):>10.2f}m{min(radii):>7.2f}m"
        )
        for finding, count in findings.most_common():
            print(f"    {count} x {finding} ...")


if __name__ == "__main__":
    main()

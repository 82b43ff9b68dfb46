"""The random track generator: FS rules over many seeds, determinism, failing fast."""

from __future__ import annotations

import hashlib
import re
import subprocess
import sys

import numpy as np
import pytest
from scipy.ndimage import uniform_filter1d

from conesim.core.polyline import Polyline
from conesim.tracks import (
    ConeKind,
    GeneratedTrack,
    Track,
    TrackFormatError,
    TrackGenerationError,
    TrackSpec,
    check_report,
    generate_track,
    load_track,
    read_track,
    write_track,
)
from conesim.tracks.generate.spec import SIZE_LENGTHS

SEEDS = range(1000, 1010)  # per size; the benchmarks use other seeds
DERIVED_WIDTH_TOLERANCE_M = 0.03  # the width derived from the cones reads up to 2-3 cm narrow


def tightest_radius(track: Track) -> float:
    """The tightest lane-centre radius [m], curvature averaged over 2 m as ``track check`` does."""
    kappa = np.abs(uniform_filter1d(track.geometry.curvature, 4, mode="wrap"))
    return float(1.0 / kappa.max())


def lane_width(track: Track) -> float:
    """The lane's width as generated [m] (in the description)."""
    match = re.search(r"([\d.]+) m wide", track.description)
    assert match is not None
    return float(match.group(1))


@pytest.mark.parametrize("size", list(SIZE_LENGTHS))
def test_generated_tracks_keep_the_fs_rules(size: str) -> None:
    """On 10 seeds of each size: a closed loop of the size's length, 3 m wide or more
    (the derived width to 3 cm), cones at most 5 m apart along each side, no crossings,
    no turn tighter than the 3 m floor (to 10 %), a gate of 4 big orange cones standing
    wider than the lane, the car behind the line; track check finds nothing else."""
    spec = TrackSpec(size=size)  # type: ignore[arg-type]
    lo, hi = spec.lengths
    for seed in SEEDS:
        track = generate_track(seed, spec)
        geometry = track.geometry
        assert track.layout == "closed" and geometry.closed
        assert lo <= track.length_m <= hi, (seed, track.length_m)
        assert lane_width(track) >= 3.0
        assert track.widths.min() >= 3.0 - DERIVED_WIDTH_TOLERANCE_M, seed
        for side in (track.left_boundary, track.right_boundary):
            gaps = np.hypot(*np.diff(np.vstack([side, side[:1]]), axis=0).T)
            assert gaps.max() <= 5.0, (seed, gaps.max())
        for line in (geometry.left_boundary, geometry.right_boundary, geometry.centreline):
            assert Polyline(line, True).crossings() == []
        assert (
            Polyline(geometry.left_boundary, True).crossings(
                Polyline(geometry.right_boundary, True)
            )
            == []
        )
        assert tightest_radius(track) >= 0.9 * spec.min_radius, seed
        gate = track.cones_of(ConeKind.BIG_ORANGE)
        assert len(gate) == 4
        centre = Polyline(track.centreline, True)
        lateral = np.abs(centre.project(gate).lateral)
        line = centre.project(track.start_finish.mean(axis=0)).station[0]
        half = 0.5 * track.widths[np.abs(centre.stations[:-1] - line).argmin()]
        assert np.all(lateral >= half + spec.gate_offset[0] - 0.05), seed
        behind = (line - centre.project(track.start_pose.xy).station[0]) % track.length_m
        assert behind == pytest.approx(4.0, abs=0.1)
        report = check_report(track)
        assert report["errors"] == [] and report["warnings"] == [], (seed, report)


def test_tight_hairpins_go_below_the_regular_ones_down_to_the_floor() -> None:
    """With every hairpin tight (tight_share 1) the tightest turn is below the
    regular 4.5 m and not below the 3 m floor (to 10 %); with none, not below 4.5 m."""
    tight = TrackSpec(hairpins=(2, 2), tight_share=1.0)
    regular = TrackSpec(hairpins=(2, 2), tight_share=0.0)
    for seed in range(5):
        track = generate_track(seed, tight)
        assert track.description.count("tight hairpin") == 2
        assert 0.9 * 3.0 <= tightest_radius(track) < 4.5
        assert tightest_radius(generate_track(seed, regular)) >= 0.9 * 4.5


def test_features_appear_over_seeds() -> None:
    """Over 10 seeds the layouts have hairpins, S-bends, chicanes and slaloms."""
    text = " ".join(generate_track(seed).description for seed in range(10))
    for feature in ("hairpin", "s_bend", "chicane", "slalom", "corner"):
        assert feature in text


def test_same_seed_same_cones_bit_for_bit() -> None:
    """The same seed and spec give the same track, twice in a process and in another process."""
    first, again = generate_track(5), generate_track(5)
    assert first == again and first.cones.tobytes() == again.cones.tobytes()
    assert generate_track(6) != first
    assert generate_track(5, TrackSpec(size="small")) != first
    code = (
        "import hashlib; from conesim.tracks import generate_track; "
        "print(hashlib.sha256(generate_track(5).cones.tobytes()).hexdigest())"
    )
    other = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert other == hashlib.sha256(first.cones.tobytes()).hexdigest()


def test_a_seed_that_cannot_make_a_track_fails_with_one_clear_error() -> None:
    """A 60-61 m lap cannot hold the features: the bounded attempts end in a
    TrackGenerationError (a TrackFormatError) naming the seed and why."""
    spec = TrackSpec(length=(60.0, 61.0), max_attempts=20)
    with pytest.raises(TrackGenerationError, match=r"seed 3: no track in 20 attempts .*60-61 m"):
        generate_track(3, spec)
    assert issubclass(TrackGenerationError, TrackFormatError)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"size": "huge"}, "TrackSpec.size = 'huge': allowed small, medium, large"),
        ({"width": (2.5, 3.0)}, r"TrackSpec.width = \(2.5, 3\) is out of range"),
        ({"length": (300.0, 200.0)}, r"TrackSpec.length = \(300, 200\) is out of range"),
        ({"tight_share": 1.5}, r"TrackSpec.tight_share = 1.5 is out of range: allowed \[0, 1\]"),
        ({"min_radius": 0.5}, r"TrackSpec.min_radius = 0.5 is out of range"),
        ({"max_spacing": 6.0}, r"TrackSpec.max_spacing = 6.0 is out of range"),
        ({"width": 3.0}, r"TrackSpec.width = 3.0: expected a pair"),
    ],
)
def test_bad_specs_are_refused(changes: dict[str, object], message: str) -> None:
    """Out-of-range or mistyped settings raise ValueError naming the field and range."""
    with pytest.raises(ValueError, match=message):
        TrackSpec(**changes)  # type: ignore[arg-type]


def test_seed_out_of_range_is_refused() -> None:
    """A seed is an integer in [0, 2**63)."""
    for seed in (-1, 2**63, 1.5, True):
        with pytest.raises(ValueError, match=r"GeneratedTrack\.seed"):
            generate_track(seed)  # type: ignore[arg-type]


def test_generated_track_writes_and_reads_back(tmp_path) -> None:
    """Written in the conesim format and read back, the track is the same, and
    ``load_track`` makes it from its recipe."""
    track = generate_track(9, TrackSpec(size="small"))
    back = read_track(write_track(track, tmp_path / "g.yaml"))
    assert back == track
    assert load_track(GeneratedTrack(9, TrackSpec(size="small"))) == track
    assert track.name == "generated-small-9"
    assert GeneratedTrack(9, TrackSpec(size="small", tight_share=0.5)).name.startswith(
        "generated-small-9-"
    )

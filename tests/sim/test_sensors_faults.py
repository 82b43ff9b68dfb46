"""Tests for sim.sensors.faults: every fault takes effect, with worked numbers.

Each test drives a sensor suite along trackdrive's centreline at 10 m/s
(the truth a car on the line would give) with the fault and without, and
checks the figure the fault names against its sampling bounds (binomial or
Poisson counts, chi-square spreads, exact sums where there is no noise).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Iterator
from functools import cache

import numpy as np
import pytest

from conesim.core.messages import ConeDetections, HeadingStamped, Imu, NavSatFix, WheelSpeed
from conesim.core.pose import Pose2D
from conesim.sim.sensors import (
    ConeFaults,
    Faults,
    GpsFaults,
    HeadingFaults,
    ImuFaults,
    SensorSuite,
    TruthSample,
    WheelSpeedFaults,
    apply_faults,
    get_profile,
)
from conesim.sim.sensors.cone_detector import ConeDetector
from conesim.sim.sensors.cone_map import ConeMap
from conesim.sim.sensors.profiles import SensorProfile
from conesim.tracks import load_track

SPEED = 10.0  # [m/s] along the centreline
RATE = 200.0  # [Hz] physics
IDEAL = get_profile("ideal")
RTK = get_profile("rtk")


@cache
def _line() -> tuple[np.ndarray, np.ndarray, ConeMap, tuple[str, ...], np.ndarray]:
    track = load_track("trackdrive")
    centre = np.asarray(track.centreline)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(centre, axis=0).T))])
    kinds = tuple(str(k) for k in track.kinds)
    cones = np.asarray(track.cones)
    return centre, s, ConeMap(cones, kinds), kinds, cones


def truths(seconds: float) -> Iterator[TruthSample]:
    """The truth at every physics step of ``seconds`` along the centreline."""
    centre, s, cmap, kinds, cones = _line()
    for k in range(1, round(seconds * RATE) + 1):
        t = k / RATE
        d = (SPEED * t) % s[-1]
        x, y = np.interp(d, s, centre[:, 0]), np.interp(d, s, centre[:, 1])
        ahead = (d + 0.5) % s[-1]
        yaw = math.atan2(
            np.interp(ahead, s, centre[:, 1]) - y, np.interp(ahead, s, centre[:, 0]) - x
        )
        pose = Pose2D(float(x), float(y), yaw)
        yield TruthSample(
            t, pose, SPEED, 0.0, cone_positions=cones, cone_kinds=kinds, cone_map=cmap
        )


def drive(profile: SensorProfile, seconds: float = 20.0) -> list[tuple[float, object]]:
    """(delivery time, message) of every message over ``seconds``."""
    suite = SensorSuite(profile, seed=3)
    return [(truth.t, m) for truth in truths(seconds) for m in suite.step(truth)]


def of(kind: type, run: list[tuple[float, object]]) -> list:
    return [m for _, m in run if isinstance(m, kind)]


def within(count: float, expected: float, sigma: float) -> bool:
    """``count`` within 4 sigma of ``expected``."""
    return abs(count - expected) <= 4.0 * sigma


def test_detection_probability_07_drops_30_percent_of_the_cones_in_range() -> None:
    """Ideal cones see every cone in range; at q = 0.7 over 200 scans (20 s):
    about 30 % fewer, within the binomial bound 4 sqrt(N 0.7 0.3)."""
    seen = sum(len(m.points) for m in of(ConeDetections, drive(IDEAL)))
    faulty = apply_faults(IDEAL, Faults(cones=ConeFaults(detection_probability=0.7)))
    kept = sum(len(m.points) for m in of(ConeDetections, drive(faulty)))
    assert seen > 1500  # about 8 cones in view per scan
    assert within(kept, 0.7 * seen, math.sqrt(seen * 0.7 * 0.3))
    assert 0.27 < 1.0 - kept / seen < 0.33


def test_false_positives_per_scan_add_their_mean_to_every_scan() -> None:
    """Two ghost cones per scan on top of ideal's none: 2 x 200 scans, Poisson bound."""
    seen = sum(len(m.points) for m in of(ConeDetections, drive(IDEAL)))
    faulty = apply_faults(IDEAL, Faults(cones=ConeFaults(false_positives_per_scan=2.0)))
    scans = of(ConeDetections, drive(faulty))
    ghosts = sum(len(m.points) for m in scans) - seen
    assert len(scans) == 201  # t = 0 is not in the drive; 0.1 s ... 20.0 s, delivered by 20 s
    assert within(ghosts, 2.0 * len(scans), math.sqrt(2.0 * len(scans)))
    assert sum(m.colours.count("unknown") for m in scans) == ghosts  # ghosts carry no colour


def test_colour_swap_reports_a_fifth_of_blue_as_yellow_and_back() -> None:
    """p = 0.2 with ideal's perfect colour: 20 % of blue labels turn yellow and 20 %
    of yellow turn blue (binomial bounds); orange is untouched."""
    clean = of(ConeDetections, drive(IDEAL))
    swap = of(ConeDetections, drive(apply_faults(IDEAL, Faults(cones=ConeFaults(
        colour_swap_probability=0.2)))))  # fmt: skip
    pairs = [
        (a, b)
        for m, n in zip(clean, swap, strict=True)
        for a, b in zip(m.colours, n.colours, strict=True)
    ]
    for true, other in (("blue", "yellow"), ("yellow", "blue")):
        labels = [b for a, b in pairs if a == true]
        swapped = labels.count(other)
        assert swapped + labels.count(true) == len(labels)
        assert within(swapped, 0.2 * len(labels), math.sqrt(len(labels) * 0.2 * 0.8))
    assert all(b == a for a, b in pairs if a in ("orange", "big_orange"))


def range_errors(profile: SensorProfile, scans: int = 100) -> np.ndarray:
    """Measured range minus 10 m of every point, for 36 cones on a 10 m ring
    around a parked car (no false positives, no occlusion)."""
    angles = np.linspace(0.0, 2.0 * math.pi, 36, endpoint=False)
    ring = 10.0 * np.column_stack([np.cos(angles), np.sin(angles)])
    config = dataclasses.replace(profile.cones, false_positive_rate=0.0, occlusion=False)
    detector = ConeDetector(config, seed=3)
    parked = Pose2D(0.0, 0.0, 0.0)
    out = []
    for k in range(scans):
        truth = TruthSample(k / config.rate, parked, cone_positions=ring, cone_kinds=("blue",) * 36)
        points = detector.capture(truth).points
        out.append(np.hypot(points[:, 0], points[:, 1]) - 10.0)
    return np.concatenate(out)


def test_cone_noise_scale_3_triples_the_range_noise() -> None:
    """rtk's 0.05 m range sigma, scaled by 3: 0.15 m (chi-square bound on ~1700 samples)."""
    faulty = apply_faults(RTK, Faults(cones=ConeFaults(noise_scale=3.0)))
    assert faulty.cones.range_sigma == pytest.approx(0.15)
    assert faulty.cones.bearing_sigma == pytest.approx(0.021)
    err = range_errors(faulty)
    assert err.size > 1500  # 19 cones in the half ring in view, 90 % detected, 100 scans
    assert err.std() == pytest.approx(0.15, rel=4.0 / math.sqrt(2 * err.size))
    assert range_errors(RTK).std() == pytest.approx(0.05, rel=4.0 / math.sqrt(2 * err.size))


def test_extra_latency_delays_every_scan_by_it() -> None:
    """rtk's 0.2 s plus 0.1 s: every scan arrives 0.3 s after its capture."""
    faulty = apply_faults(RTK, Faults(cones=ConeFaults(extra_latency=0.1)))
    run = drive(faulty, 5.0)
    lags = [t - m.header.stamp for t, m in run if isinstance(m, ConeDetections)]
    assert lags and max(lags) == pytest.approx(0.3) and min(lags) == pytest.approx(0.3)


def test_gps_dropout_10_to_12_s_loses_the_20_fixes_captured_then() -> None:
    """At 10 Hz the window [10, 12) holds 20 captures: each is a NO_FIX (NaN) message."""
    faulty = apply_faults(RTK, Faults(gps=GpsFaults(dropouts=((10.0, 12.0),))))
    fixes = of(NavSatFix, drive(faulty, 15.0))
    lost = [f.header.stamp for f in fixes if math.isnan(f.latitude)]
    assert len(lost) == 20
    assert min(lost) == pytest.approx(10.0) and max(lost) == pytest.approx(11.9)


def fix_errors(profile: SensorProfile, seconds: float = 20.0) -> tuple[np.ndarray, np.ndarray]:
    """(stamps, (n, 2) east/north errors [m]) of the fixes, against the truth."""
    from conesim.core.geodesy import gps_to_local_cartesian

    truth = {round(s.t, 6): s.antenna_pose for s in truths(seconds)}
    fixes = of(NavSatFix, drive(profile, seconds))
    t = np.array([f.header.stamp for f in fixes])
    err = np.array([
        np.asarray(gps_to_local_cartesian(f.latitude, f.longitude)) -
        (truth[round(f.header.stamp, 6)].x, truth[round(f.header.stamp, 6)].y)
        for f in fixes
    ])  # fmt: skip
    return t, err


def test_gps_multipath_rate_01_size_5_moves_a_tenth_of_the_fixes_5_m() -> None:
    """Ideal fixes (no noise), 10 % outliers of 5 m: the error is 0 or 5 m, and the
    share of 5 m within its binomial bound over 200 fixes."""
    faulty = apply_faults(IDEAL, Faults(gps=GpsFaults(multipath_rate=0.1, multipath_size=5.0)))
    _, err = fix_errors(faulty)
    size = np.hypot(err[:, 0], err[:, 1])
    outliers = int(np.sum(size > 1.0))
    assert np.all((size < 1e-6) | (np.abs(size - 5.0) < 1e-6))
    assert within(outliers, 0.1 * len(size), math.sqrt(len(size) * 0.1 * 0.9))


def test_gps_bias_drift_walks_the_fix_off_at_its_rate() -> None:
    """Ideal fixes, drift (0.1, -0.05) m/s from 5 s: exact at 0 before, at t = 15 s
    the fix is 1.0 m east and 0.5 m south of the truth."""
    drift = Faults(gps=GpsFaults(bias_drift=(0.1, -0.05), bias_drift_start=5.0))
    t, err = fix_errors(apply_faults(IDEAL, drift))
    assert np.abs(err[t <= 5.0]).max() < 1e-6
    at = int(np.argmin(np.abs(t - 15.0)))
    assert err[at] == pytest.approx([1.0, -0.5], abs=1e-6)


def test_imu_bias_and_noise_scale() -> None:
    """Ideal IMU plus 0.01 rad/s and (0.2, -0.1) m/s^2: every sample off by exactly
    that; rtk's gyro noise times 2 doubles its spread, the stated variance stays."""
    faulty = apply_faults(IDEAL, Faults(imu=ImuFaults(gyro_bias=0.01, accel_bias=(0.2, -0.1))))
    samples = of(Imu, drive(faulty, 5.0))
    assert len(samples) == 501  # the first at the first step, then every 10 ms
    assert all(m.yaw_rate == pytest.approx(0.01, abs=1e-9) for m in samples)
    assert all(m.accel_x == pytest.approx(0.2, abs=1e-9) for m in samples)
    assert all(m.accel_y == pytest.approx(-0.1, abs=1e-9) for m in samples)
    noisy = of(Imu, drive(apply_faults(RTK, Faults(imu=ImuFaults(noise_scale=2.0))), 20.0))
    gyro = np.array([m.yaw_rate for m in noisy])
    sigma = RTK.imu.gyro_sigma
    assert gyro.std() == pytest.approx(2.0 * sigma, rel=4.0 / math.sqrt(2 * gyro.size))
    assert noisy[0].yaw_rate_variance == pytest.approx(sigma**2)


def test_heading_dropout_3_to_4_s_loses_20_headings() -> None:
    """At 20 Hz the window [3, 4) holds 20 captures: none is published; the rest
    are the same headings as without the dropout."""
    clean = of(HeadingStamped, drive(RTK, 6.0))
    faulty = apply_faults(RTK, Faults(heading=HeadingFaults(dropouts=((3.0, 4.0),))))
    kept = of(HeadingStamped, drive(faulty, 6.0))
    assert len(clean) - len(kept) == 20
    assert kept == [m for m in clean if not 3.0 - 1e-9 <= m.header.stamp < 4.0 - 1e-9]


def test_wheel_slip_005_at_10_mps_is_05_mps_of_noise() -> None:
    """Ideal wheel speed plus slip 0.05 at 10 m/s: spread 0.5 m/s (chi-square bound),
    the stated variance still the encoder's (0)."""
    faulty = apply_faults(IDEAL, Faults(wheel_speed=WheelSpeedFaults(slip_sigma=0.05)))
    speeds = np.array([m.speed for m in of(WheelSpeed, drive(faulty, 20.0))])
    assert speeds.size == 1001
    assert speeds.std() == pytest.approx(0.5, rel=4.0 / math.sqrt(2 * speeds.size))
    assert speeds.mean() == pytest.approx(SPEED, abs=4 * 0.5 / math.sqrt(speeds.size))
    assert of(WheelSpeed, drive(faulty, 0.1))[0].variance == 0.0


ONE_EACH = {
    "cones": [ConeFaults(detection_probability=0.7), ConeFaults(false_positives_per_scan=1.0),
              ConeFaults(colour_swap_probability=0.1), ConeFaults(noise_scale=2.0),
              ConeFaults(extra_latency=0.05)],
    "gps": [GpsFaults(dropouts=((1.0, 2.0),)), GpsFaults(multipath_rate=0.1),
            GpsFaults(bias_drift=(0.1, 0.0), bias_drift_start=2.0)],
    "imu": [ImuFaults(gyro_bias=0.01), ImuFaults(accel_bias=(0.1, 0.2)),
            ImuFaults(noise_scale=3.0)],
}  # fmt: skip


def test_faults_combine_in_any_order() -> None:
    """Each sensor's faults applied one at a time, in every order, give the profile
    that all of them at once give (no two touch the same field)."""
    combined = {
        section: dataclasses.replace(
            type(parts[0])(),
            **{
                f.name: getattr(p, f.name)
                for p in parts
                for f in dataclasses.fields(p)
                if getattr(p, f.name) != getattr(type(p)(), f.name)
            },
        )
        for section, parts in ONE_EACH.items()
    }
    at_once = apply_faults(RTK, Faults(**combined))
    for order in itertools.permutations(ONE_EACH["cones"]):
        config = RTK.cones
        for fault in order:
            config = fault.apply(config)
        assert config == at_once.cones
    for section in ("gps", "imu"):
        for order in itertools.permutations(ONE_EACH[section]):
            config = getattr(RTK, section)
            for fault in order:
                config = fault.apply(config)
            assert config == getattr(at_once, section)
    assert Faults(**combined).active == (
        "gps.dropouts", "gps.multipath_rate", "gps.bias_drift", "gps.bias_drift_start",
        "imu.gyro_bias", "imu.accel_bias", "imu.noise_scale",
        "cones.detection_probability", "cones.false_positives_per_scan",
        "cones.colour_swap_probability", "cones.noise_scale", "cones.extra_latency",
    )  # fmt: skip


def test_no_fault_is_the_profile_itself() -> None:
    """Faults() changes nothing: the very same profile object (runs stay bit for bit)."""
    for profile in (IDEAL, RTK, get_profile("consumer")):
        assert apply_faults(profile, Faults()) is profile


def test_detection_probability_scales_the_range_law() -> None:
    """rtk's p(r) = 1 - r/100 times 0.7 is 0.7 - 0.007 r: at 10 m, 0.63."""
    cones = ConeFaults(detection_probability=0.7).apply(RTK.cones)
    assert cones.detection_probability(np.array([0.0, 10.0])) == pytest.approx([0.7, 0.63])


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: ConeFaults(detection_probability=1.2), "ConeFaults.detection_probability"),
        (lambda: ConeFaults(false_positives_per_scan=-1.0), "[0, 100] [1/scan]"),
        (lambda: ConeFaults(false_positives_per_scan=1e9), "[0, 100] [1/scan]"),
        (lambda: ConeFaults(noise_scale=math.nan), "ConeFaults.noise_scale"),
        (lambda: GpsFaults(dropouts=((12.0, 10.0),)), "GpsFaults.dropouts[0]"),
        (lambda: GpsFaults(dropouts=((-1.0, 1.0),)), "0 <= start < end"),
        (lambda: GpsFaults(multipath_rate=2.0), "GpsFaults.multipath_rate"),
        (lambda: GpsFaults(bias_drift=(1.0,)), "GpsFaults.bias_drift"),  # type: ignore[arg-type]
        (lambda: ImuFaults(gyro_bias=math.inf), "ImuFaults.gyro_bias"),
        (lambda: HeadingFaults(dropouts=((1.0,),)), "HeadingFaults.dropouts[0]"),  # type: ignore[arg-type]
        (lambda: WheelSpeedFaults(slip_sigma=-0.1), "WheelSpeedFaults.slip_sigma"),
    ],
)
def test_bad_faults_name_the_field_and_range(make: object, message: str) -> None:
    """A fault out of range is refused when it is made, naming the field."""
    with pytest.raises(ValueError, match=None) as info:
        make()  # type: ignore[operator]
    assert message in str(info.value) and "allowed" in str(info.value)

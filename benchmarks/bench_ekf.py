"""The fusion EKF: cost per call, and the Monte Carlo figures of issue 4 section 3.

(a) Cost: median microseconds of one predict (an IMU sample), one update
(heading, wheel speed, GPS fix), a GPS fix 0.12 s late (restore and replay),
and ``estimate`` at the broadcast time (at a new stamp, and again at the same
stamp, which the filter answers from its cache), on a filter driving a circle.

(b) Monte Carlo: seeded runs of the car driving one lap of the autocross
track, truth and messages from ``sim.world.World`` (a pure-pursuit driver on
the true centreline steers from ground truth; only the estimator is measured).
For each sensor profile the table gives the position RMSE against the raw GPS
RMS error, the heading RMSE (over the lap after a 2 s warm-up, and after
10 s, once the heading-bias state has converged), the NEES (3 dof, x y yaw,
at 20 Hz) band fraction
and mean, and the GPS NIS (2 dof) mean and band fraction, bands from
chi2(N n) / N for the N runs. Then a 5 s GPS dropout at speed and 1 % of fixes
replaced by 20 m multipath jumps. If the world cannot be built, the same table
is computed on the synthetic car of ``localization.ekf.synthetic`` with the
profiles' noise figures as white noise, and is labelled SYNTHETIC.

Run: ``python benchmarks/bench_ekf.py [--runs 50] [--fault-runs 20] [--synthetic]
[--cost-only | --skip-cost]`` (the full run takes several minutes).
"""

from __future__ import annotations

import argparse
import logging
import math
import statistics
import time
import timeit
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2

from conesim.core import messages as rosmsg
from conesim.core.pose import Pose2D, wrap_angle
from conesim.localization.ekf import EkfConfig, FusionEkf, RejectReason, for_profile
from conesim.localization.ekf.synthetic import Path, SensorNoise, fix_message, make_truth, messages
from conesim.localization.gps_to_local import gps_to_local_cartesian

FloatArray = NDArray[np.float64]
# (time [s], true antenna pose, messages delivered)
Tick = tuple[float, Pose2D, list[rosmsg.Message]]
TickSource = Callable[[str, int, "Faults"], Iterator[Tick]]

GRID = 200.0  # [Hz] physics / truth grid
EVAL_EVERY = 10  # grid steps between evaluations (20 Hz, the broadcaster's rate)
WARMUP = 2.0  # [s] excluded from the RMSE and NEES (initialisation transient)
LATE = 10.0  # [s] the heading RMSE is also given after this
OUTLIER_THRESHOLD = 10.0  # [m] a fix this far from the truth is a multipath jump
PROFILES = ("rtk", "consumer_white", "consumer", "ideal")
DROPOUT = (15.0, 5.0)  # (start [s], duration [s])
REPEATS = 5
ANTENNA = rosmsg.FRAME_GPS_ANTENNA


# -- (a) cost -----------------------------------------------------------------------------


def _imu(t: float) -> rosmsg.Imu:
    """An IMU sample of a car on a 10 m circle at 10 m/s."""
    return rosmsg.Imu(rosmsg.Header(t, ANTENNA), 1.0, 0.0, 10.0, 5.6e-6, 5.1e-4)


def _truth_circle(t: float) -> tuple[float, float, float]:
    return 10.0 * math.sin(t), 10.0 * (1.0 - math.cos(t)), float(wrap_angle(t))


def _started_filter(t_end: float) -> FusionEkf:
    """An rtk filter that has driven the circle with all sensors until ``t_end`` [s]."""
    ekf = FusionEkf(for_profile("rtk"))
    for k in range(round(t_end * 100) + 1):
        t = k / 100
        x, y, yaw = _truth_circle(t)
        antenna, reference = rosmsg.Header(t, ANTENNA), rosmsg.Header(t, rosmsg.FRAME_REFERENCE)
        ekf.process(_imu(t))
        if k % 2 == 0:
            ekf.process(rosmsg.WheelSpeed(antenna, 10.0, 0.0025))
        if k % 5 == 0:
            ekf.process(rosmsg.HeadingStamped(reference, yaw, 1.9e-5))
        if k % 10 == 0:
            ekf.process(fix_message(t, x, y, 0.025))
    return ekf


def _median_us(setup: Callable[[], Callable[[], object]], number: int) -> float:
    """Median over REPEATS of the mean CPU time of ``number`` calls of a freshly set-up call [us].

    CPU time (``time.process_time``), so that other work on a shared machine
    does not count.
    """
    runs = []
    for _ in range(REPEATS):
        call = setup()
        runs.append(timeit.timeit(call, number=number, timer=time.process_time) / number * 1e6)
    return statistics.median(runs)


def bench_cost() -> dict[str, float]:
    """Microseconds per call of the filter's steps (see the module docstring)."""
    n = 2000

    def predicts() -> Callable[[], object]:
        ekf = _started_filter(1.0)
        samples = iter([_imu(1.0 + (k + 1) / 100) for k in range(n)])
        return lambda: ekf.process(next(samples))

    def updates(msg: rosmsg.Message) -> Callable[[], Callable[[], object]]:
        def setup() -> Callable[[], object]:
            ekf = _started_filter(1.0)
            ekf.process(_imu(1.01))  # the newest entry: no predict, no replay
            return lambda: ekf.process(msg)

        return setup

    def late_fixes() -> Callable[[], object]:
        ekf = _started_filter(1.0)
        stream: list[rosmsg.Message] = []
        for k in range(1, n + 1):
            t = 1.0 + k / 100
            stream.append(_imu(t))
            if k % 10 == 0:
                stamp = t - 0.12
                x, y, _ = _truth_circle(stamp)
                stream.append(fix_message(stamp, x, y, 0.025))
        msgs = iter(stream)
        return lambda: ekf.process(next(msgs))

    def estimates() -> Callable[[], object]:
        ekf = _started_filter(1.0)
        return lambda: ekf.estimate(1.03)

    def fresh_estimates() -> Callable[[], object]:
        ekf = _started_filter(1.0)
        stamps = iter([1.03 + k * 1e-6 for k in range(n)])  # a new stamp each call: no cache
        return lambda: ekf.estimate(next(stamps))

    heading = rosmsg.HeadingStamped(rosmsg.Header(1.01, rosmsg.FRAME_REFERENCE), 1.01, 1e-2)
    wheel = rosmsg.WheelSpeed(rosmsg.Header(1.01, rosmsg.FRAME_GPS_ANTENNA), 10.0, 1.0)
    x, y, _ = _truth_circle(1.01)
    fix = fix_message(1.01, x, y, 1.0)
    stream_calls = n + n // 10
    # The late-fix stream mixes IMU samples and fixes: subtract the predicts.
    mixed = _median_us(late_fixes, stream_calls) * stream_calls
    predict = _median_us(predicts, n)
    return {
        "predict (one IMU sample)": predict,
        "update: heading (1 dof)": _median_us(updates(heading), n),
        "update: wheel speed (1 dof)": _median_us(updates(wheel), n),
        "update: GPS fix (2 dof, with projection)": _median_us(updates(fix), n),
        "GPS fix 0.12 s late (replay ~12 predicts)": (mixed - n * predict) / (n // 10),
        "estimate 30 ms ahead (a new stamp)": _median_us(fresh_estimates, n),
        "estimate 30 ms ahead (same stamp again: cached)": _median_us(estimates, n),
    }


# -- (b) Monte Carlo: sources of truth and messages ---------------------------------------


@dataclass(frozen=True)
class Faults:
    """GPS faults of a scenario: a dropout window and a multipath probability."""

    dropout: tuple[float, float] | None = None  # (start [s], duration [s])
    multipath: float = 0.0  # [-] probability per fix


class CentrelineDriver:
    """Pure pursuit on the true centreline with a curvature speed limit (ground truth steers).

    Args:
        centreline: (m, 2) [m], a loop in driving order.
        curvature: (m,) [1/m].
        wheelbase: [m].
        v_max: speed cap [m/s].
        a_lat: lateral acceleration for the speed limit [m/s^2].
    """

    def __init__(
        self,
        centreline: FloatArray,
        curvature: FloatArray,
        wheelbase: float,
        v_max: float = 12.0,
        a_lat: float = 6.0,
    ) -> None:
        self.path = np.asarray(centreline, dtype=float)
        kappa = np.abs(np.asarray(curvature, dtype=float))
        limit = np.minimum(v_max, np.sqrt(a_lat / np.maximum(kappa, 1e-6)))
        # look 10 m (20 points) ahead for the speed limit
        self.v_target = np.min([np.roll(limit, -k) for k in range(20)], axis=0)
        self.wheelbase = wheelbase
        self.i = 0

    def command(self, x: float, y: float, yaw: float, speed: float) -> tuple[float, float]:
        """(steer [rad], acceleration [m/s^2]) for the CG pose and speed."""
        n = len(self.path)
        window = (self.i + np.arange(-10, 40)) % n
        d = np.hypot(self.path[window, 0] - x, self.path[window, 1] - y)
        self.i = int(window[np.argmin(d)])
        look = 3.0 + 0.3 * speed
        j = (self.i + round(look / 0.5)) % n
        dx, dy = self.path[j, 0] - x, self.path[j, 1] - y
        alpha = math.atan2(dy, dx) - yaw
        steer = math.atan2(2.0 * self.wheelbase * math.sin(alpha), math.hypot(dx, dy))
        return steer, 3.0 * (float(self.v_target[self.i]) - speed)


def world_ticks(profile: str, seed: int, faults: Faults) -> Iterator[Tick]:
    """One lap of autocross in ``sim.world.World``: every physics step's truth and messages."""
    from conesim.sim.sensors import get_profile, override
    from conesim.sim.world import World, WorldConfig
    from conesim.tracks import load_track

    changes: dict[str, object] = {"cones.enabled": False}
    if faults.dropout is not None:
        changes["gps.dropouts"] = (faults.dropout,)
    if faults.multipath:
        changes["gps.multipath_probability"] = faults.multipath
    track = load_track("autocross")
    sensors = override(get_profile(profile), changes)
    world = World(track, WorldConfig(sensors=sensors), seed=seed)
    first = world.reset(seed)
    geometry = track.geometry
    driver = CentrelineDriver(
        geometry.centreline, geometry.curvature, world.config.vehicle.wheelbase
    )
    yield world.time, world.state.antenna_pose(), first
    travelled = 0.0
    while travelled < geometry.length_m and world.time < 120.0:
        s = world.state
        world.set_command(*driver.command(s.x, s.y, s.yaw, s.vx))
        msgs = world.step().messages
        travelled += world.state.vx * world.dt
        yield world.time, world.state.antenna_pose(), msgs


# The profiles' noise figures (sim.sensors.profiles) as white noise, for the fallback.
SYNTHETIC_NOISE = {
    "ideal": SensorNoise(gps=1e-3, heading=1e-4, gyro=1e-5, accel=1e-4, wheel=1e-3),
    "rtk": SensorNoise(gps=0.025, heading=math.radians(0.25), gps_latency=0.05,
                       heading_latency=0.05, wheel_scale=0.005),
    "consumer_white": SensorNoise(gps=2.5 / 1.1774, gps_rate=5.0, gps_latency=0.12,
                                  heading=math.radians(math.sqrt(5.0)), heading_rate=10.0,
                                  heading_latency=0.12, gyro=8.7e-4, accel=0.024,
                                  wheel_scale=0.005),
}  # fmt: skip


def synthetic_ticks(profile: str, seed: int, faults: Faults) -> Iterator[Tick]:
    """The synthetic car for 40 s with the profile's noise figures (white)."""
    truth = _SYNTHETIC_TRUTH
    rng = np.random.default_rng(seed)
    n_fix = int(40.0 * SYNTHETIC_NOISE[profile].gps_rate)
    pick = rng.random(n_fix) < faults.multipath
    every = 1.0 / SYNTHETIC_NOISE[profile].gps_rate
    outliers = frozenset(float(k * every) for k in np.flatnonzero(pick))
    gap = None
    if faults.dropout is not None:
        gap = (faults.dropout[0], faults.dropout[0] + faults.dropout[1])
    stream = messages(truth, SYNTHETIC_NOISE[profile], rng, outliers=outliers, gps_gap=gap)
    pending = next(stream, None)
    for k, t in enumerate(truth.t.tolist()):
        delivered: list[rosmsg.Message] = []
        while pending is not None and pending[0] <= t + 1e-9:
            delivered.append(pending[1])
            pending = next(stream, None)
        yield t, truth.pose(float(truth.t[k])), delivered


_SYNTHETIC_TRUTH = make_truth(Path(), duration=40.0)


def synthetic_config(profile: str) -> EkfConfig:
    """The profile's filter settings without the bias states the white fallback lacks."""
    return replace(for_profile(profile), gps_bias_sigma=0.0, heading_bias_sigma=0.0)


# -- (b) Monte Carlo: one run, many runs ----------------------------------------------------


@dataclass
class RunResult:
    """What one run recorded (evaluations at 20 Hz; fixes as they were processed)."""

    times: list[float] = field(default_factory=list)
    position_error: list[float] = field(default_factory=list)  # [m]
    yaw_error: list[float] = field(default_factory=list)  # [rad]
    nees: list[float] = field(default_factory=list)
    gps_nis: list[float] = field(default_factory=list)
    raw_error: list[float] = field(default_factory=list)  # [m], good fixes
    outliers: int = 0
    outliers_rejected: int = 0
    good_rejected: int = 0


def run_once(ticks: Iterator[Tick], config: EkfConfig) -> RunResult:
    """Feed one run to a fresh filter; evaluate it against the truth at 20 Hz."""
    ekf = FusionEkf(config)
    out = RunResult()
    truth_at: dict[int, Pose2D] = {}
    for t, pose, msgs in ticks:
        k = round(t * GRID)
        truth_at[k] = pose
        for msg in msgs:
            result = ekf.process(msg)
            if not isinstance(msg, rosmsg.NavSatFix) or msg.status == rosmsg.NavSatStatus.NO_FIX:
                continue
            true = truth_at[round(msg.header.stamp * GRID)]
            point = gps_to_local_cartesian(msg)
            error = math.hypot(point.x - true.x, point.y - true.y)
            gated = result is not None and result.reason == RejectReason.NIS_GATE
            if error > OUTLIER_THRESHOLD:
                out.outliers += 1
                out.outliers_rejected += gated
                continue
            out.raw_error.append(error)
            out.good_rejected += gated
            if result is not None and result.nis is not None:
                out.gps_nis.append(result.nis)
        if k % EVAL_EVERY == 0 and ekf.initialised:
            est = ekf.estimate(t)
            e = est.pose_error(pose)
            out.times.append(t)
            out.position_error.append(math.hypot(e[0], e[1]))
            out.yaw_error.append(float(e[2]))
            out.nees.append(est.nees(pose))
    return out


def band(n: int, dof: int) -> tuple[float, float]:
    """95 % band of the mean of n chi2(dof) values [-]."""
    lo, hi = chi2.ppf([0.025, 0.975], n * dof)
    return float(lo / n), float(hi / n)


@dataclass(frozen=True)
class Summary:
    """Monte Carlo figures of one profile and scenario."""

    runs: int
    position_rmse: float  # [m]
    raw_rms: float  # [m]
    heading_rmse_deg: float  # [deg]
    heading_rmse_late_deg: float  # [deg] after LATE s (heading-bias states converged)
    nees_mean: float
    nees_in_band: float  # [-] fraction of evaluation times
    nis_mean: float
    nis_in_band: float  # [-] fraction of fix indices
    results: list[RunResult]

    def error_at(self, t: float) -> float:
        """RMS over runs of the position error at time ``t`` [m]."""
        values = []
        for r in self.results:
            i = int(np.argmin(np.abs(np.asarray(r.times) - t)))
            values.append(r.position_error[i])
        return float(np.sqrt(np.mean(np.square(values))))


def summarise(results: list[RunResult]) -> Summary:
    """Pool the runs: RMSE after the warm-up, NEES and NIS band fractions across runs."""
    n = len(results)
    length = min(len(r.times) for r in results)
    times = np.asarray(results[0].times[:length])
    keep = times >= times[0] + WARMUP
    late = times >= times[0] + LATE
    pos = np.array([r.position_error[:length] for r in results])[:, keep]
    yaw = np.array([r.yaw_error[:length] for r in results])[:, keep]
    nees = np.array([r.nees[:length] for r in results])[:, keep].mean(axis=0)
    n_fix = min(len(r.gps_nis) for r in results)
    nis = np.array([r.gps_nis[1:n_fix] for r in results]).mean(axis=0)
    lo3, hi3 = band(n, 3)
    lo2, hi2 = band(n, 2)
    raw = np.concatenate([r.raw_error for r in results])
    return Summary(
        runs=n,
        position_rmse=float(np.sqrt(np.mean(pos**2))),
        raw_rms=float(np.sqrt(np.mean(raw**2))),
        heading_rmse_deg=math.degrees(float(np.sqrt(np.mean(yaw**2)))),
        heading_rmse_late_deg=math.degrees(float(np.sqrt(np.mean(yaw[:, late[keep]] ** 2)))),
        nees_mean=float(nees.mean()),
        nees_in_band=float(np.mean((nees >= lo3) & (nees <= hi3))),
        nis_mean=float(nis.mean()),
        nis_in_band=float(np.mean((nis >= lo2) & (nis <= hi2))),
        results=results,
    )


def monte_carlo(
    source: TickSource, config: Callable[[str], EkfConfig], profile: str, runs: int, faults: Faults
) -> Summary:
    """``runs`` seeded runs of one profile and scenario."""
    cfg = config(profile)
    return summarise([run_once(source(profile, seed, faults), cfg) for seed in range(runs)])


# -- the report -----------------------------------------------------------------------------


def print_cost() -> None:
    """Table (a)."""
    print("(a) cost per call, median of", REPEATS, "repeats [CPU us]")
    for name, us in bench_cost().items():
        print(f"  {name:<48s} {us:8.1f}")


def print_monte_carlo(
    source: TickSource,
    config: Callable[[str], EkfConfig],
    args: argparse.Namespace,
    label: str,
    *,
    synthetic: bool,
) -> None:
    """Tables (b)."""
    profiles = [p for p in PROFILES if not synthetic or p in SYNTHETIC_NOISE]
    print(f"\n(b) Monte Carlo, {label}: {args.runs} runs per profile")
    head = (
        f"  {'profile':<15s}{'pos RMSE':>10s}{'raw GPS':>10s}{'ratio':>7s}{'hdg RMSE':>10s}"
        f"{'>10 s':>9s}{'NEES':>7s}{'in band':>9s}{'NIS':>6s}{'in band':>9s}"
    )
    print(head + "\n  " + "-" * (len(head) - 2))
    nominal: dict[str, Summary] = {}
    for profile in profiles:
        s = monte_carlo(source, config, profile, args.runs, Faults())
        nominal[profile] = s
        ratio = f"{s.position_rmse / s.raw_rms:7.2f}" if s.raw_rms > 1e-6 else f"{'-':>7s}"
        print(
            f"  {profile:<15s}{s.position_rmse:9.3f}m{s.raw_rms:9.3f}m{ratio}"
            f"{s.heading_rmse_deg:7.3f}deg{s.heading_rmse_late_deg:6.3f}deg"
            f"{s.nees_mean:7.2f}{s.nees_in_band:8.0%} {s.nis_mean:6.2f}{s.nis_in_band:8.0%}"
        )
    lo3, hi3 = band(args.runs, 3)
    lo2, hi2 = band(args.runs, 2)
    print(f"  bands for N = {args.runs}: NEES [{lo3:.2f}, {hi3:.2f}], NIS [{lo2:.2f}, {hi2:.2f}]")

    start, duration = DROPOUT
    print(f"\n  GPS dropout {start:.0f}-{start + duration:.0f} s, {args.fault_runs} runs")
    for profile in ("rtk", "consumer_white"):
        if profile not in profiles:
            continue
        s = monte_carlo(source, config, profile, args.fault_runs, Faults(dropout=DROPOUT))
        end = start + duration
        print(
            f"  {profile:<15s} error at its end {s.error_at(end - 0.05):.3f} m (RMS), "
            f"3 s after {s.error_at(end + 3.0):.3f} m, nominal RMSE "
            f"{nominal[profile].position_rmse:.3f} m"
        )

    print(f"\n  1 % of fixes 20 m multipath, {args.fault_runs} runs")
    for profile in ("rtk", "consumer_white"):
        if profile not in profiles:
            continue
        s = monte_carlo(source, config, profile, args.fault_runs, Faults(multipath=0.01))
        base = summarise(nominal[profile].results[: args.fault_runs])  # the same seeds
        injected = sum(r.outliers for r in s.results)
        rejected = sum(r.outliers_rejected for r in s.results)
        good = sum(r.good_rejected for r in s.results)
        print(
            f"  {profile:<15s} {rejected}/{injected} jumps rejected, {good} good fixes gated, "
            f"RMSE {s.position_rmse:.3f} m = {s.position_rmse / base.position_rmse:.2f} x nominal"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=50, help="runs per profile (default 50)")
    parser.add_argument("--fault-runs", type=int, default=20, help="runs per fault scenario")
    parser.add_argument("--synthetic", action="store_true", help="skip the world")
    parser.add_argument("--skip-cost", action="store_true", help="only the Monte Carlo")
    parser.add_argument("--cost-only", action="store_true", help="only the cost per call")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)
    if not args.skip_cost:
        print_cost()
    if args.cost_only:
        return
    source: TickSource = world_ticks
    config: Callable[[str], EkfConfig] = for_profile
    label = "sim.world, autocross, one lap"
    if not args.synthetic:
        try:
            for _ in zip(range(3), world_ticks("rtk", 0, Faults()), strict=False):
                pass
        except Exception as err:  # the world is optional here: fall back, say why
            print(f"\nsim.world unavailable ({type(err).__name__}: {err}); using the synthetic car")
            args.synthetic = True
    if args.synthetic:
        source, config, label = synthetic_ticks, synthetic_config, "SYNTHETIC car (white noise)"
    print_monte_carlo(source, config, args, label, synthetic=args.synthetic)


if __name__ == "__main__":
    main()

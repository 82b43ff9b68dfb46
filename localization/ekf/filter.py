"""The fusion EKF: filterpy's ``ExtendedKalmanFilter`` fed GPS, heading, wheel speed and IMU.

State and models: :mod:`localization.ekf.model` (the antenna pose, body
velocity, gyro bias, wheel-speed scale and optional Gauss-Markov sensor
errors; the IMU is the input), the motion model
:func:`localization.ekf.kernels.motion_terms` (through
:class:`~localization.ekf.model.MotionStep`) and the observation models
:mod:`localization.ekf.observation`. How filterpy is used, given its pitfalls
(REFERENCES.md, "filterpy 2.0.0"):

* ``x`` is (n, 1) and every ``z`` is (m, 1), never 1-D.
* ``predict`` is linear in filterpy, so :class:`_FilterpyEkf` overrides
  ``predict_x`` with the nonlinear motion model (x' = f(x, u, dt), computed
  with ``F`` and ``Q`` by :class:`~localization.ekf.model.MotionStep` and set
  before each ``predict``).
* Angles: the heading residual is wrapped (``residual=``), and yaw is wrapped
  after every predict and every update; ``P`` is re-symmetrised after both.

Each message goes through, in order:

1. checks (:mod:`.measurements`): a NaN, a NO_FIX fix, a bad covariance or a
   wrong frame is rejected, counted and logged before it touches the state;
   so is a message stamped more than ``max_stamp_jump`` after the newest one
   (too new: a clock glitch would otherwise move the filter's time ahead and
   make every later message too old). ``clock_jump_messages`` messages in a
   row too old or too new mean the clock itself jumped (a restarted
   simulation, a looped log): the filter resets and initialises again;
2. initialisation, until a fix and a heading within ``init_sync_tolerance``
   of each other have arrived (then the state is set at the fix's stamp and
   the messages after it are replayed);
3. its place in the :class:`~.history.History` by stamp: the state is
   predicted to the stamp with the IMU input held (zero-order hold) and then
   updated, or, for a message stamped before the newest one, the state before
   its stamp is restored and everything after it replayed;
4. for updates, the NIS gate: y' S^-1 y against ``chi2.ppf(gate_probability,
   m)``; a gated measurement leaves the state as it was. After
   ``max_consecutive_gps_rejections`` gated fixes in a row the filter assumes
   it has diverged, resets, and initialises again.

Without GPS (a dropout) nothing special happens: the IMU keeps predicting,
the heading and wheel speed keep updating, and the position covariance grows
until the next fix, which the gate measures against that grown covariance.

Written for speed (the closed loop sends ~190 messages a simulated second,
and every late one replays a few more), with the same numbers as the plain
formulation (``tests/localization/test_ekf_regression.py``):

* predict: x', F and Q in one pass over floats (:class:`~.model.MotionStep`);
* update: the constant GPS and heading Jacobians built once (by their
  observation models' functions); the NIS on floats; the gate's residual is
  the one handed to filterpy;
* snapshots share the filter's arrays instead of copying them: filterpy
  replaces ``x`` and ``P`` on every predict and update, this module writes
  only into the arrays one has just made (the yaw wrap), and a snapshot makes
  its arrays read-only, so a write through an alias would raise;
* replay is deferred: the entries after a late message are replayed when
  something needs the newer state (the next message stamped after them,
  ``estimate``, ``health``), so a fix and a heading stamped together and
  delivered together replay once instead of twice;
* ``estimate(t)`` is cached per stamp and state (the env asks several times
  per control step), and shares its arrays (the snapshot's, or the ones just
  predicted for it) instead of copying them;
* ``P`` is re-symmetrised by a compiled kernel (:mod:`.kernels`), the same
  operations as ``0.5 * (P + P.T)``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from typing import TYPE_CHECKING, Any

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from numpy.typing import NDArray
from scipy.stats import chi2

from conesim.core.messages import ConeDetections, Message
from conesim.localization.ekf import augmented, kernels
from conesim.localization.ekf import model as m
from conesim.localization.ekf.augmented import MapState
from conesim.localization.ekf.config import EkfConfig
from conesim.localization.ekf.estimate import Estimate
from conesim.localization.ekf.health import Health, RejectReason, Sensor, UpdateResult
from conesim.localization.ekf.history import Entry, History, Snapshot, order_key
from conesim.localization.ekf.measurements import InvalidMessage, Measurement, to_measurement
from conesim.localization.ekf.observation import OBSERVATIONS

if TYPE_CHECKING:
    from conesim.localization.cones.association import Association
    from conesim.localization.cones.update import ConeUpdate, StackedModel
    from conesim.localization.slam.book import MapBook
    from conesim.localization.slam.update import SlamUpdate

ESTIMATE_CACHE_SIZE = 8  # estimates kept (per stamp) for repeated calls

FloatArray = NDArray[np.float64]

_log = logging.getLogger("conesim.localization.ekf")

# Per-sample input covariance assumed before the first IMU sample [rad^2/s^2, m^2/s^4].
NO_IMU_COV = np.diag([1.0, 100.0, 100.0])
NO_IMU_COV.flags.writeable = False
NO_IMU_INPUT = np.zeros(3)  # the input held before the first IMU sample
NO_IMU_INPUT.flags.writeable = False  # read-only as every sample's (one kernel specialisation)


class NotInitialisedError(RuntimeError):
    """The filter has no state yet (it waits for a fix and a heading)."""


def _nis(y: FloatArray, s: FloatArray) -> float:
    """y' S^-1 y for a 1- or 2-dof innovation, on floats."""
    if y.shape[0] == 1:
        y0 = y.item(0)
        return y0 * (y0 / s.item(0))
    y0, y1 = y.item(0), y.item(1)
    a, b, c, d = s.item(0), s.item(1), s.item(2), s.item(3)
    return (y0 * (d * y0 - b * y1) + y1 * (a * y1 - c * y0)) / (a * d - b * c)


def _freeze(a: FloatArray) -> FloatArray:
    """Make an array read-only (a snapshot shares it) and return it."""
    a.flags.writeable = False
    return a


class _FilterpyEkf(ExtendedKalmanFilter):
    """filterpy's EKF with the nonlinear motion model as ``predict_x``.

    The motion model's x' is computed together with F and Q
    (:class:`~localization.ekf.model.MotionStep`) and handed over in
    ``x_next`` before each ``predict``.

    Args:
        n: state dimension.
    """

    def __init__(self, n: int) -> None:
        super().__init__(dim_x=n, dim_z=2)
        self.x: FloatArray = np.zeros((n, 1))
        self.x_next: FloatArray = self.x  # f(x, u, dt) for the coming predict

    def predict_x(self, u: Any = 0) -> None:
        """x = f(x, u, dt) (filterpy would do F x + B u)."""
        self.x = self.x_next


def propagate(snap: Snapshot, t: float, step: m.MotionStep) -> tuple[FloatArray, FloatArray]:
    """Predict a held state to ``t`` [s] >= ``snap.t`` without touching the filter.

    Returns:
        (x (n, 1), P (n, n)) at ``t``, yaw wrapped, P symmetric; the snapshot's
        own (read-only) arrays if ``t`` is its time.
    """
    dt = t - snap.t
    if dt <= 0.0:
        return snap.x, snap.P
    x1, f, q = step(snap.x, snap.u, snap.u_cov, dt)
    x1[m.YAW, 0] = m.wrap_yaw(x1.item(m.YAW))
    return x1, kernels.symmetrised(np.dot(f, snap.P).dot(f.T) + q)


class FusionEkf:
    """GPS + heading + wheel speed + IMU fusion into the pose of ``gps_antenna``.

    Args:
        config: noise model, gating, history; default :class:`EkfConfig`.
        cones: the cone map and its update (``cones`` mode,
            :mod:`localization.cones`): each ``ConeDetections`` scan then
            updates the pose; or the map built while driving (``slam``
            mode, :mod:`localization.slam`): the landmarks then join the
            state after the vehicle's, held beside filterpy's vehicle
            block in :mod:`.augmented`'s compressed form; None ignores the
            scans.

    Attributes:
        config: the settings.
        layout: the state layout.
    """

    def __init__(
        self, config: EkfConfig | None = None, cones: ConeUpdate | SlamUpdate | None = None
    ) -> None:
        self.config = config or EkfConfig()
        self._scans: ConeUpdate | SlamUpdate | None = cones  # makes the scans' measurements
        self._slam: SlamUpdate | None = None
        self._cones: ConeUpdate | None = None
        if getattr(cones, "maps_landmarks", False):
            self._slam = cones  # type: ignore[assignment]
        else:
            self._cones = cones  # type: ignore[assignment]
        map_bias = cones is not None and cones.config.map_bias_sigma > 0.0
        self.layout = dataclasses.replace(self.config.layout, map_bias=map_bias)
        self._health = Health()
        self._process = self.config.process_model(self.layout)
        self._step = m.MotionStep(self._process)
        kernels.warm_up(self._step, NO_IMU_INPUT, NO_IMU_COV)
        self._gates = {dof: float(chi2.ppf(self.config.gate_probability, dof)) for dof in (1, 2)}
        self._ekf = _FilterpyEkf(self.layout.n)
        self._constant_h = {  # H of the sensors whose H does not depend on the state
            sensor: _freeze(obs.jacobian(self._ekf.x, self.layout))
            for sensor, obs in OBSERVATIONS.items()
            if obs.constant
        }
        self._history: History | None = None
        self._deferred: list[Entry] = []
        self.reset()

    # -- public ------------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget the state; the filter initialises again from the next fix and heading."""
        self._replay_deferred()  # its gate decisions still count in ``health``
        self._history = None
        self._pending: list[Measurement] = []
        self._t = 0.0
        self._u = NO_IMU_INPUT
        self._u_cov = NO_IMU_COV
        self._gps_rejections_in_row = 0
        self._stale_in_row = 0  # messages in a row rejected as too old or too new
        self._estimates: dict[float | None, tuple[Snapshot, Estimate]] = {}
        self._book: MapBook | None = None if self._slam is None else self._slam.empty_book()
        self._map: MapState | None = None if self._slam is None else MapState.empty(self.layout.n)

    @property
    def health(self) -> Health:
        """Counters of accepted and rejected messages (a deferred replay is counted first)."""
        self._replay_deferred()
        if self._history is not None and self._history.latest.book is not None:
            self._health.landmarks = self._history.latest.book.counts()
        return self._health

    def landmark_state(self) -> tuple[FloatArray, FloatArray, MapBook] | None:
        """The map being built (``slam`` mode): positions (L, 2) [m], their covariances
        (L, 2, 2) [m^2] and the book (colours, counts); None in other modes or before
        initialisation."""
        if self._slam is None or self._history is None:
            return None
        self._replay_deferred()
        snap = self._history.latest
        assert snap.book is not None and snap.map is not None
        return snap.map.x.reshape(-1, 2).copy(), np.array(snap.map.blocks()), snap.book

    @property
    def initialised(self) -> bool:
        """Whether the filter has a state."""
        return self._history is not None

    @property
    def time(self) -> float | None:
        """Stamp of the newest message applied [s], or None before initialisation."""
        if self._history is None:
            return None
        return self._deferred[-1].measurement.stamp if self._deferred else self._t

    def process(self, msg: Message) -> UpdateResult | None:
        """Hand over one message (any order of stamps within the history window).

        Args:
            msg: an ``Imu``, ``NavSatFix``, ``HeadingStamped`` or ``WheelSpeed``
                (and ``ConeDetections`` with a cone map); other message types
                are ignored.

        Returns:
            What came of it, or None for a type the filter does not use.
            Before initialisation, good messages are kept and reported accepted.
        """
        try:
            meas = to_measurement(msg, self.config)
            if meas is None and self._scans is not None and isinstance(msg, ConeDetections):
                meas = self._scans.measurement(msg)
        except InvalidMessage as err:
            self._health.reject(err.sensor, err.reason, err.stamp, err.detail)
            return UpdateResult(err.sensor, err.stamp, False, err.reason)
        if meas is None:
            return None
        result = self._too_new(meas) or self._take(meas)
        stale = result.reason in (RejectReason.TOO_OLD, RejectReason.TOO_NEW)
        self._stale_in_row = self._stale_in_row + 1 if stale else 0
        if self._stale_in_row >= self.config.clock_jump_messages:
            self._reset_because(
                f"{self._stale_in_row} messages in a row too old or too new for the "
                f"filter's time, the last stamped {meas.stamp:.6f} s: the clock jumped"
            )
        return result

    def _reset_because(self, why: str) -> None:
        """Log why, count the reset, and reset."""
        _log.warning("%s; resetting the filter", why)
        self._health.resets += 1
        self.reset()

    def _too_new(self, meas: Measurement) -> UpdateResult | None:
        """Reject ``meas`` if it is stamped ``max_stamp_jump`` after the newest message."""
        if self._history is not None:
            newest = self.time
        else:
            newest = self._pending[-1].stamp if self._pending else None
        if newest is None or meas.stamp <= newest + self.config.max_stamp_jump:
            return None
        detail = f"{meas.stamp - newest:.6g} s after the newest message ({newest!r} s)"
        self._health.reject(meas.sensor, RejectReason.TOO_NEW, meas.stamp, detail)
        return UpdateResult(meas.sensor, meas.stamp, False, RejectReason.TOO_NEW)

    def _take(self, meas: Measurement) -> UpdateResult:
        """Hold ``meas`` for initialisation, or apply it at its place in time."""
        history = self._history
        if history is None:
            return self._hold_for_init(meas)
        deferred = self._deferred
        if deferred and not order_key(meas) < order_key(deferred[0].measurement):
            self._replay_deferred()  # ``meas`` goes after them: they are needed now
        result = self._insert(meas, history)
        if self._gps_rejections_in_row >= self.config.max_consecutive_gps_rejections:
            self._reset_because(
                f"{self._gps_rejections_in_row} GPS fixes in a row gated at {meas.stamp:.6f} s"
            )
        return result

    def estimate(self, stamp: float | None = None) -> Estimate:
        """The estimate at ``stamp`` (default: the newest message's stamp).

        A later stamp is predicted forward with the last IMU input held; an
        earlier one (within the history) starts from the state held then.
        Repeated calls for the same stamp and state return the same object.

        Raises:
            NotInitialisedError: before initialisation.
            ValueError: ``stamp`` is not finite or older than the history.
        """
        if stamp is not None and not math.isfinite(stamp):
            raise ValueError(f"FusionEkf.estimate: stamp must be finite [s], got {stamp!r}")
        history = self._history
        if history is None:
            raise NotInitialisedError("the EKF waits for a GPS fix and a heading")
        self._replay_deferred()
        snap = history.latest
        if stamp is not None and stamp < snap.t:
            snap = history.snapshot_at(stamp)
        cached = self._estimates.get(stamp)
        if cached is not None and cached[0] is snap:
            return cached[1]
        t = snap.t if stamp is None else stamp
        x, p = propagate(snap, t, self._step)
        yaw_rate = snap.u.item(0) - x.item(m.GYRO_BIAS)
        # x, p: the snapshot's (read-only) arrays or new ones only this estimate holds.
        est = Estimate.from_state(t, x, p, yaw_rate, self.layout.names, copy=False)
        if len(self._estimates) >= ESTIMATE_CACHE_SIZE:
            self._estimates.clear()
        self._estimates[stamp] = (snap, est)
        return est

    # -- initialisation ----------------------------------------------------------------------

    def _hold_for_init(self, meas: Measurement) -> UpdateResult:
        """Keep a message until a fix and a heading allow initialisation
        (one older than the window of those kept is rejected as too old)."""
        if self._pending and meas.stamp < self._pending[-1].stamp - self.config.history_window:
            detail = f"older than the messages held to initialise ({self._pending[0].stamp!r} s)"
            self._health.reject(meas.sensor, RejectReason.TOO_OLD, meas.stamp, detail)
            return UpdateResult(meas.sensor, meas.stamp, False, RejectReason.TOO_OLD)
        self._pending.append(meas)
        self._pending.sort(key=order_key)
        horizon = self._pending[-1].stamp - self.config.history_window
        self._pending = [p for p in self._pending if p.stamp >= horizon]
        if meas.sensor in (Sensor.GPS, Sensor.HEADING):
            self._try_init()
        return UpdateResult(meas.sensor, meas.stamp, True)

    def _nearest(self, sensor: Sensor, stamp: float) -> Measurement | None:
        """The pending message of ``sensor`` nearest ``stamp`` within the sync tolerance."""
        found = [p for p in self._pending if p.sensor == sensor]
        if not found:
            return None
        best = min(found, key=lambda p: abs(p.stamp - stamp))
        return best if abs(best.stamp - stamp) <= self.config.init_sync_tolerance else None

    def _try_init(self) -> None:
        """Initialise at the newest fix's stamp if a heading is close enough in time."""
        fixes = [q for q in self._pending if q.sensor == Sensor.GPS]
        if not fixes:
            return
        fix = fixes[-1]
        heading = self._nearest(Sensor.HEADING, fix.stamp)
        if heading is None:
            return
        wheel = self._nearest(Sensor.WHEEL_SPEED, fix.stamp)
        imus = [q for q in self._pending if q.sensor == Sensor.IMU and q.stamp <= fix.stamp]
        u, u_cov = (imus[-1].z, imus[-1].cov) if imus else (NO_IMU_INPUT, NO_IMU_COV)
        x, p = self._initial_state(fix, heading, wheel)
        base = Snapshot(fix.stamp, _freeze(x), _freeze(p), u, u_cov, self._book, self._map)
        history = History(base, self.config.history_window)
        self._history = history
        self._restore(base)
        used = [q for q in (fix, heading, wheel) if q is not None]
        for q in used:
            self._health.accept(q.sensor)
        later = [q for q in self._pending if q.stamp > fix.stamp and all(q is not k for k in used)]
        self._health.discarded_before_init += len(self._pending) - len(later) - len(used)
        self._pending = []
        skew = heading.stamp - fix.stamp
        _log.info("EKF initialised at %.6f s (heading %+.3f s from the fix)", fix.stamp, skew)
        for q in later:  # in stamp order: each goes last, nothing is replayed
            self._insert(q, history)

    def _initial_state(
        self, fix: Measurement, heading: Measurement, wheel: Measurement | None
    ) -> tuple[FloatArray, FloatArray]:
        """(x (n, 1), P (n, n)) at the fix's stamp from the first fix, heading, wheel speed.

        Position and yaw are the measurements; the yaw variance grows by
        ``init_yaw_rate_bound`` times the heading's stamp offset. vx is the wheel
        speed (or 0 with ``init_speed_sigma``), vy 0 with a sideslip-scaled sigma,
        the gyro bias 0, the wheel scale 1. A modelled sensor bias starts at 0 with
        its stationary variance and the state it corrupts at the measured value,
        with the bias's variance added and a correlation of -1 x that variance
        (measured = state + bias).
        """
        cfg = self.config
        n = self.layout.n
        x = np.zeros((n, 1))
        p = np.zeros((n, n))
        x[m.X : m.Y + 1] = fix.z
        p[m.X : m.Y + 1, m.X : m.Y + 1] = fix.cov
        x[m.YAW, 0] = heading.z[0, 0]
        skew = abs(heading.stamp - fix.stamp)
        p[m.YAW, m.YAW] = heading.cov[0, 0] + (cfg.init_yaw_rate_bound * skew) ** 2
        if wheel is not None:
            speed = abs(float(wheel.z[0, 0]))
            x[m.VX, 0] = wheel.z[0, 0]
            p[m.VX, m.VX] = wheel.cov[0, 0] + (cfg.init_wheel_scale_sigma * speed) ** 2
        else:
            speed = cfg.init_speed_sigma
            p[m.VX, m.VX] = cfg.init_speed_sigma**2
        p[m.VY, m.VY] = (cfg.init_lateral_speed_sigma + cfg.init_sideslip_sigma * speed) ** 2
        p[m.GYRO_BIAS, m.GYRO_BIAS] = cfg.init_gyro_bias_sigma**2
        x[m.WHEEL_SCALE, 0] = 1.0
        p[m.WHEEL_SCALE, m.WHEEL_SCALE] = cfg.init_wheel_scale_sigma**2
        g = self.layout.gps_bias_index
        if g is not None:
            sb2 = cfg.gps_bias_sigma**2 * np.eye(2)
            p[m.X : m.Y + 1, m.X : m.Y + 1] += sb2
            p[g : g + 2, g : g + 2] = sb2
            p[m.X : m.Y + 1, g : g + 2] = p[g : g + 2, m.X : m.Y + 1] = -sb2
        h = self.layout.heading_bias_index
        if h is not None:
            sh2 = cfg.heading_bias_sigma**2
            p[m.YAW, m.YAW] += sh2
            p[h, h] = sh2
            p[m.YAW, h] = p[h, m.YAW] = -sh2
        b = self.layout.map_bias_index
        if b is not None and self._cones is not None:
            p[b : b + 2, b : b + 2] = self._cones.config.map_bias_sigma**2 * np.eye(2)
        if self._slam is not None and self._slam.start is not None:
            self._start_at(x, p, fix, heading)
        return x, p

    def _start_at(
        self, x: FloatArray, p: FloatArray, fix: Measurement, heading: Measurement
    ) -> None:
        """Put the pose on the known start (``slam`` mode), in place: the map's frame is the
        start's. The fix and the heading then measure their sensors' errors: with a bias
        state, bias = measured - start, of variance R + start's and correlation -start's
        (measured = state + bias); without one they update the pose as usual later."""
        slam = self._slam
        assert slam is not None and slam.start is not None
        start = slam.start
        sxy2, syaw2 = slam.slam.start_sigma**2, slam.slam.start_yaw_sigma**2
        g, h = self.layout.gps_bias_index, self.layout.heading_bias_index
        x[m.X, 0], x[m.Y, 0], x[m.YAW, 0] = start.x, start.y, start.yaw
        pose = slice(m.X, m.YAW + 1)
        p[pose, :] = 0.0
        p[:, pose] = 0.0
        p[m.X, m.X] = p[m.Y, m.Y] = sxy2
        p[m.YAW, m.YAW] = syaw2
        if g is not None:
            x[g : g + 2] = fix.z - [[start.x], [start.y]]
            p[g : g + 2, g : g + 2] = fix.cov + sxy2 * np.eye(2)
            p[m.X : m.Y + 1, g : g + 2] = p[g : g + 2, m.X : m.Y + 1] = -sxy2 * np.eye(2)
        if h is not None:
            x[h, 0] = m.wrap_yaw(heading.z.item(0) - start.yaw)
            p[h, h] = heading.cov.item(0) + syaw2
            p[m.YAW, h] = p[h, m.YAW] = -syaw2

    # -- the history -------------------------------------------------------------------------

    def _insert(self, meas: Measurement, history: History) -> UpdateResult:
        """Apply a message at its place in time; what came after it is replayed (or deferred).

        The caller has replayed any deferred entries unless ``meas`` sorts
        before all of them; those then join the entries after ``meas``.
        """
        if history.too_old(meas):
            detail = f"older than the history ({history.base.t!r} s)"
            self._health.reject(meas.sensor, RejectReason.TOO_OLD, meas.stamp, detail)
            return UpdateResult(meas.sensor, meas.stamp, False, RejectReason.TOO_OLD)
        later = history.cut(history.position(meas)) + self._deferred
        self._deferred = []
        if later:
            self._health.replays += 1
            self._restore(history.latest)
        result = self._apply(meas, history)
        self._count(result)
        if not later:
            history.prune()
            return result
        newest = later[-1].measurement.stamp
        self._deferred = later
        if later[0].measurement.stamp >= newest - history.window:
            history.prune(newest)  # drops nothing from ``later``: it may wait
        else:
            self._replay_deferred()  # pruning would drop some of ``later``: replay now
        return result

    def _replay_deferred(self) -> None:
        """Replay the entries a late message was put before, and prune the history."""
        later = self._deferred
        if not later:
            return
        self._deferred = []
        history = self._history
        assert history is not None  # entries are only deferred while initialised
        for entry in later:
            replayed = self._apply(entry.measurement, history)
            if replayed.accepted != entry.accepted or replayed.reason != entry.reason:
                sensor = entry.measurement.sensor
                self._health.revise(sensor, entry.reason, replayed.reason, replayed.stamp)
            if entry.cones is not None:
                self._health.cones.add(entry.cones, -1)
            if replayed.cones is not None:
                self._health.cones.add(replayed.cones)
        history.prune()

    def _apply(self, meas: Measurement, history: History) -> UpdateResult:
        """Predict to the message's stamp, use it, and record the state after it.

        An IMU sample is the motion over the interval that ends at its stamp (a
        MEMS IMU reports the average over its sample period; the simulator's is
        the acceleration over the last physics step), so it becomes the input
        *before* predicting to its stamp. Other messages are predicted to with
        the newest input held.
        """
        if meas.sensor == Sensor.IMU:
            self._u, self._u_cov = meas.z, meas.cov
            self._predict_to(meas.stamp)
            result = UpdateResult(Sensor.IMU, meas.stamp, True)
        else:
            self._predict_to(meas.stamp)
            result = self._update(meas)
        entry = Entry(
            meas, self._snapshot(), result.accepted, result.nis, result.reason, result.cones
        )
        history.append(entry)
        return result

    def _count(self, result: UpdateResult) -> None:
        """Count a first decision; track gated fixes in a row."""
        if result.accepted:
            self._health.accept(result.sensor)
        if result.cones is not None:
            self._health.cones.add(result.cones)
        if result.sensor == Sensor.GPS:
            self._gps_rejections_in_row = 0 if result.accepted else self._gps_rejections_in_row + 1

    # -- the two Kalman steps ----------------------------------------------------------------

    def _predict_to(self, t: float) -> None:
        """Predict with the held IMU input from the filter's time to ``t`` [s]."""
        dt = t - self._t
        if dt <= 0.0:
            return
        ekf = self._ekf
        ekf.x_next, ekf.F, ekf.Q = self._step(ekf.x, self._u, self._u_cov, dt)
        ekf.predict(u=self._u)
        if self._map is not None:
            self._map = augmented.predicted(self._map, ekf.F)
        self._tidy()
        self._t = t

    def _update(self, meas: Measurement) -> UpdateResult:
        """Gate one measurement by its NIS and, if it passes, apply it."""
        if meas.sensor == Sensor.CONES:
            return self._update_cones(meas)
        ekf = self._ekf
        hx, jac, y = self._observe(meas, ekf.x)
        s = np.dot(jac, ekf.P).dot(jac.T) + meas.cov
        nis = _nis(y, s)
        dof = y.shape[0]
        if not nis <= self._gates[dof]:
            detail = f"NIS {nis:.3g} > {self._gates[dof]:.3g} ({dof} dof)"
            self._health.reject(meas.sensor, RejectReason.NIS_GATE, meas.stamp, detail)
            return UpdateResult(meas.sensor, meas.stamp, False, RejectReason.NIS_GATE, nis, dof)
        self._correct(meas.z, hx, jac, meas.cov, y)
        return UpdateResult(meas.sensor, meas.stamp, True, None, nis, dof)

    def _correct(
        self, z: FloatArray, hx: FloatArray, jac: FloatArray, cov: FloatArray, y: FloatArray
    ) -> None:
        """The Kalman update with a gated measurement of the vehicle: filterpy's; with
        landmarks (``slam``), then the map's part from its gain (:func:`.augmented.measured`)."""
        ekf = self._ekf
        ekf.update(z, lambda _x: jac, lambda _x: hx, R=cov, residual=lambda _z, _h: y)
        if self._map is not None:
            self._map = augmented.measured(self._map, jac, ekf.K, ekf.SI, y, frozen=self._frozen())
        self._tidy()

    def _frozen(self) -> bool:
        """Whether the map is frozen (``slam``, the loop closed): the landmarks stay put."""
        return self._book is not None and self._book.closed

    def _update_cones(self, meas: Measurement) -> UpdateResult:
        """Associate a cone scan with the map, gate the set by its joint NIS, apply it;
        building the map (``slam``), then the map step (:mod:`localization.slam.update`)."""
        ekf = self._ekf
        slam = self._slam
        if slam is None:
            cones = self._cones
            assert cones is not None  # cone measurements are made only with a map
            found = cones.associate(ekf.x, ekf.P, meas, self.layout)
            model = cones.model(ekf.x, meas, found, self.layout) if len(found) else None
            return self._scan_update(meas, found, cones, model)
        book, lmap = self._book, self._map
        assert book is not None and lmap is not None
        found = slam.associate(ekf.x, ekf.P, lmap, meas, book)
        model = slam.model(ekf.x, lmap, meas, found) if len(found) else None
        result = self._scan_update(meas, found, slam, model)
        assert self._map is not None
        self._map, self._book = slam.map_step(
            ekf.x, ekf.P, self._map, meas, found, used=result.accepted, book=book
        )
        return result

    def _scan_update(
        self,
        meas: Measurement,
        found: Association,
        cones: ConeUpdate | SlamUpdate,
        model: StackedModel | None,
    ) -> UpdateResult:
        """Gate a scan's associated detections (their ``model``, None without any) by their
        joint NIS and apply them."""
        ekf = self._ekf
        counts = found.counts
        if model is None:
            detail = f"none of {len(meas.z)} detections associated"
            self._health.reject(Sensor.CONES, RejectReason.NO_ASSOCIATION, meas.stamp, detail)
            return UpdateResult(
                Sensor.CONES, meas.stamp, False, RejectReason.NO_ASSOCIATION, cones=counts
            )
        jac = model.jacobian
        y = model.z - model.hx
        terms = None
        if self._map is None:
            s = np.dot(jac, ekf.P).dot(jac.T) + model.cov
        else:  # H over the vehicle and the matched landmarks' entries
            rows = augmented.entries(found.landmarks)
            terms = augmented.scan_terms(ekf.P, self._map, jac, rows, model.cov)
            s = terms.s
        nis = float(np.dot(y.T, np.linalg.solve(s, y)).item())
        dof = y.shape[0]
        gate = cones.joint_gate(dof)
        if not nis <= gate:
            counts.scans_gated, counts.ambiguous = 1, counts.ambiguous + counts.matched
            counts.matched = 0
            detail = f"joint NIS {nis:.3g} > {gate:.3g} ({dof} dof)"
            self._health.reject(Sensor.CONES, RejectReason.NIS_GATE, meas.stamp, detail)
            return UpdateResult(
                Sensor.CONES, meas.stamp, False, RejectReason.NIS_GATE, nis, dof, counts
            )
        counts.nis_sum, counts.dof_sum = nis, dof
        lo, hi = cones.nis_band(dof)
        counts.nis_in_band = int(lo <= nis <= hi)
        if terms is None:
            self._correct(model.z, model.hx, jac, model.cov, y)
        else:
            assert self._map is not None
            ekf.x, ekf.P, self._map = augmented.scan_update(
                ekf.x, ekf.P, self._map, y, terms, frozen=self._frozen()
            )
            self._tidy()
        return UpdateResult(Sensor.CONES, meas.stamp, True, None, nis, dof, counts)

    def _observe(
        self, meas: Measurement, x: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(h(x), H, residual z - h(x), wrapped for the heading) of a measurement.

        From the sensor's observation model (:mod:`.observation`); a constant
        H is the one built when the filter was.
        """
        obs = OBSERVATIONS[meas.sensor]
        hx = obs.h(x, self.layout)
        jac = self._constant_h.get(meas.sensor)
        if jac is None:
            jac = obs.jacobian(x, self.layout)
        return hx, jac, obs.residual(meas.z, hx)

    def _tidy(self) -> None:
        """Wrap yaw and re-symmetrise P after a predict or an update (both new arrays)."""
        ekf = self._ekf
        ekf.x[m.YAW, 0] = m.wrap_yaw(ekf.x.item(m.YAW))
        ekf.P = kernels.symmetrised(ekf.P)  # 0.5 * (P + P'), compiled

    def _snapshot(self) -> Snapshot:
        """The filter's state, sharing its arrays (made read-only)."""
        ekf = self._ekf
        return Snapshot(
            self._t, _freeze(ekf.x), _freeze(ekf.P), self._u, self._u_cov, self._book, self._map
        )

    def _restore(self, snap: Snapshot) -> None:
        """Load a snapshot into the filter (its arrays are replaced, never written, from here)."""
        self._ekf.x = snap.x
        self._ekf.P = snap.P
        self._t = snap.t
        self._u = snap.u
        self._u_cov = snap.u_cov
        self._book = snap.book
        self._map = snap.map

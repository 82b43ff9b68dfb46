"""Noise processes of the sensor models, each a few lines and written by hand.

They are three textbook recursions (Kalibr's IMU noise model; Maybeck,
*Stochastic Models, Estimation and Control*, vol. 1, ch. 4), short enough that a
dependency would cost more than it saves:

* Discrete white noise from a continuous noise density ``N`` (e.g. a gyro's
  angle random walk, [rad/s/sqrt(Hz)] = [rad/sqrt(s)]) sampled every ``dt``::

      sigma_d = N / sqrt(dt)

* First-order Gauss-Markov bias with stationary std ``sigma`` and correlation
  time ``tau``, discretised exactly for any step ``dt``::

      phi     = exp(-dt / tau)
      b[k+1]  = phi * b[k] + sigma * sqrt(1 - phi^2) * w[k],   w ~ N(0, 1)

  started from its stationary law b[0] ~ N(0, sigma^2), so
  Var(b[k]) = sigma^2 and Corr(b[k], b[k+1]) = phi at every k.

* Bias random walk with density ``K`` [unit/sqrt(s)]::

      b[k+1] = b[k] + K * sqrt(dt) * w[k],   so Var(b[k] - b[0]) = K^2 * t

  AirSim's IMU model (``ImuSimple.hpp``) drives it with
  ``K = bias_instability / sqrt(tau)``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.sim.sensors.validation import check_non_negative, check_positive


def white_sigma(density: float, dt: float) -> float:
    """Std of discrete white noise sampled every ``dt`` from a noise density.

    Args:
        density: noise density [unit/sqrt(Hz)] (= [unit*sqrt(s)]).
        dt: sample period [s].

    Returns:
        sigma_d = density / sqrt(dt) [unit].

    >>> round(white_sigma(0.01, 0.01), 12)
    0.1
    """
    check_positive("white_sigma", "dt", dt, "[s]")
    return density / math.sqrt(dt)


class GaussMarkov:
    """First-order Gauss-Markov process, exactly discretised (see module docstring).

    The process is held as plain floats (``state``): the GPS and heading
    models step theirs at every capture, on one or two numbers, where numpy's
    cost per call exceeds the work (the same operations, component by
    component).

    Args:
        sigma: stationary std [unit], >= 0.
        tau: correlation time [s], > 0.
        rng: the generator of this process's own stream.
        dim: number of independent components (e.g. 2 for east/north).

    Attributes:
        state: the process now, dim floats.
    """

    def __init__(self, sigma: float, tau: float, rng: np.random.Generator, dim: int = 1) -> None:
        check_non_negative("GaussMarkov", "sigma", sigma)
        check_positive("GaussMarkov", "tau", tau, "[s]")
        self.sigma = sigma
        self.tau = tau
        self._rng = rng
        self._shape = (dim,)
        self.state: tuple[float, ...] = tuple(
            [sigma * w for w in rng.standard_normal(dim).tolist()]
        )

    @property
    def value(self) -> NDArray[np.float64]:
        """The process now, shape (dim,) (a new array)."""
        return np.array(self.state)

    def step(self, dt: float) -> tuple[float, ...]:
        """Advance by ``dt`` [s] (>= 0) and return the new value, dim floats."""
        if not (dt >= 0.0 and math.isfinite(dt)):
            check_non_negative("GaussMarkov.step", "dt", dt, "[s]")
        phi = math.exp(-dt / self.tau)
        w = self._rng.standard_normal(self._shape).tolist()
        k = self.sigma * math.sqrt(1.0 - phi * phi)
        self.state = tuple([phi * b + k * wi for b, wi in zip(self.state, w, strict=True)])
        return self.state


class BiasRandomWalk:
    """Random-walk bias ``b += K sqrt(dt) w`` starting at zero (a calibrated sensor).

    The bias is held as plain floats (``state``): the IMU steps two walks at
    every capture, where numpy's cost per call on one or two numbers exceeds
    the work (the same operations, component by component).

    Args:
        density: random-walk density K [unit/sqrt(s)], >= 0.
        rng: the generator of this process's own stream.
        dim: number of independent components.

    Attributes:
        state: the bias now, dim floats.
    """

    def __init__(self, density: float, rng: np.random.Generator, dim: int = 1) -> None:
        check_non_negative("BiasRandomWalk", "density", density)
        self.density = density
        self._rng = rng
        self._shape = (dim,)
        self.state: tuple[float, ...] = (0.0,) * dim

    @property
    def value(self) -> NDArray[np.float64]:
        """The bias now, shape (dim,) (a new array)."""
        return np.array(self.state)

    def step(self, dt: float) -> tuple[float, ...]:
        """Advance by ``dt`` [s] (>= 0) and return the new value, dim floats."""
        if not (dt >= 0.0 and math.isfinite(dt)):
            check_non_negative("BiasRandomWalk.step", "dt", dt, "[s]")
        if self.density != 0.0:
            k = self.density * math.sqrt(dt)
            w = self._rng.standard_normal(self._shape).tolist()
            self.state = tuple([b + k * wi for b, wi in zip(self.state, w, strict=True)])
        # else b + 0 * w is b bit for bit (b starts at +0 and w is finite), so
        # nothing is drawn: the walk's stream is its own (no other draw moves)
        # and its density is fixed for its life (the IMU calibrated to zero,
        # every step of the ideal and rtk profiles; no per-step draw for it).
        return self.state

"""What a random track is made of: the generator's settings and the three sizes.

Figures from REFERENCES.md, "Formula Student tracks": track width >= 3 m,
cone spacing <= 5 m, lap 200-500 m, straights <= 80 m, constant turns <= 50 m
diameter, hairpins >= 9 m outside diameter, 4 big orange cones at the
start/finish. Radii here are of the lane's centre: a hairpin of centre
radius r in a lane w wide has an outside diameter 2 r + w, so the FS minimum
in a 3 m lane is r = 3 m, which is also about the tightest the car turns
(``VehicleParams``: ~3 m at the rear axle at full lock).
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, field, fields
from typing import Literal, get_args

from conesim.tracks.errors import TrackFormatError

Size = Literal["small", "medium", "large"]
"""The three sizes of track, by lap length."""

SIZE_LENGTHS: dict[str, tuple[float, float]] = {
    "small": (200.0, 280.0),
    "medium": (280.0, 380.0),
    "large": (380.0, 500.0),
}
"""Lap length range [m] of each size."""
SIZE_HAIRPINS: dict[str, tuple[int, int]] = {"small": (1, 2), "medium": (1, 3), "large": (2, 4)}
"""How many hairpins each size has, (fewest, most)."""

FS_MIN_WIDTH_M = 3.0  # REFERENCES.md: track width >= 3 m
FS_MAX_SPACING_M = 5.0  # REFERENCES.md: cone spacing <= 5 m
FS_MAX_STRAIGHT_M = 80.0  # REFERENCES.md: straights <= 80 m
FS_MAX_CONSTANT_TURN_RADIUS_M = 25.0  # REFERENCES.md: constant turns <= 50 m diameter
FS_HAIRPIN_OUTSIDE_DIAMETER_M = 9.0  # REFERENCES.md: hairpins >= 9 m outside diameter
SEED_LIMIT = 2**63


class TrackGenerationError(TrackFormatError):
    """No track could be made for this seed and spec (the message names both and why)."""


@dataclass(frozen=True)
class TrackSpec:
    """The settings of the random track generator.

    Attributes:
        size: ``small`` (200-280 m), ``medium`` (280-380 m) or ``large``
            (380-500 m; FS: a lap of 200-500 m): the default lap length
            range and hairpin count.
        length: lap length range [m]; None: the size's.
        width: range of the lane's width [m], one width per track (FS: >= 3 m).
        hairpins: (fewest, most) hairpins; None: the size's.
        hairpin_radius: range of the hairpins' lane-centre radius [m]
            (4.5 m: a 9 m diameter at the lane's centre, wider than the FS
            rule's 9 m outside diameter).
        tight_share: the share of hairpins tighter than ``hairpin_radius``,
            down to ``min_radius`` [-].
        min_radius: the tightest lane-centre radius anywhere [m]: what the
            car can still turn (3 m; in a 3 m lane the FS minimum too).
        gate_offset: range of how far the big orange gate cones stand outside
            the lane's edges [m] (real gates stand wider than the lane).
        max_spacing: cone spacing on straights [m] (FS: <= 5 m).
        min_spacing: cone spacing in the tightest corners [m].
        leg_gap: the least distance between the edges of two parts of the
            track that are not the same bend [m].
        max_attempts: layouts tried before the seed is given up [-].
    """

    size: Size = "medium"
    length: tuple[float, float] | None = None  # [m]
    width: tuple[float, float] = (3.0, 3.5)  # [m]
    hairpins: tuple[int, int] | None = None  # [-]
    hairpin_radius: tuple[float, float] = (4.5, 7.0)  # [m]
    tight_share: float = 0.25  # [-]
    min_radius: float = 3.0  # [m]
    gate_offset: tuple[float, float] = (0.5, 1.2)  # [m]
    max_spacing: float = 4.5  # [m]
    min_spacing: float = 1.0  # [m]
    leg_gap: float = 2.0  # [m]
    max_attempts: int = 200  # [-]

    def __post_init__(self) -> None:
        if self.size not in get_args(Size):
            raise ValueError(f"TrackSpec.size = {self.size!r}: allowed {', '.join(get_args(Size))}")
        for name in ("length", "width", "hairpins", "hairpin_radius", "gate_offset"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _pair(name, value))
        _check("min_radius", self.min_radius, 1.0, 50.0, "m")
        _check("leg_gap", self.leg_gap, 0.5, 10.0, "m")
        _range("length", self.lengths, 50.0, 2000.0, "m")
        _range("width", self.width, FS_MIN_WIDTH_M, 2 * self.min_radius - self.leg_gap, "m")
        _range("hairpins", self.hairpin_counts, 0, 10, "")
        top = FS_MAX_CONSTANT_TURN_RADIUS_M
        _range("hairpin_radius", self.hairpin_radius, self.min_radius, top, "m")
        _check("tight_share", self.tight_share, 0.0, 1.0, "")
        _range("gate_offset", self.gate_offset, 0.0, 3.0, "m")
        _check("max_spacing", self.max_spacing, self.min_spacing, FS_MAX_SPACING_M, "m")
        _check("min_spacing", self.min_spacing, 0.5, self.max_spacing, "m")
        if isinstance(self.max_attempts, bool) or not isinstance(self.max_attempts, int):
            raise ValueError(f"TrackSpec.max_attempts = {self.max_attempts!r}: expected an integer")
        _check("max_attempts", self.max_attempts, 1, 10_000, "")

    @property
    def lengths(self) -> tuple[float, float]:
        """The lap length range [m] (the size's unless ``length`` is given)."""
        return self.length if self.length is not None else SIZE_LENGTHS[self.size]

    @property
    def hairpin_counts(self) -> tuple[int, int]:
        """(fewest, most) hairpins (the size's unless ``hairpins`` is given)."""
        if self.hairpins is None:
            return SIZE_HAIRPINS[self.size]
        return int(self.hairpins[0]), int(self.hairpins[1])

    def changes(self) -> dict[str, object]:
        """The fields that differ from the defaults, for names and files."""
        default = TrackSpec(size=self.size)
        return {
            f.name: getattr(self, f.name)
            for f in fields(self)
            if getattr(self, f.name) != getattr(default, f.name) or f.name == "size"
        }


@dataclass(frozen=True)
class GeneratedTrack:
    """A generated track named by its seed and spec: what a scenario's
    ``track: {generate: {seed: S, ...}}`` holds.

    Attributes:
        seed: the generator's seed, an integer in [0, 2**63).
        spec: the generator's settings.
    """

    seed: int = 0
    spec: TrackSpec = field(default_factory=TrackSpec)

    def __post_init__(self) -> None:
        if isinstance(self.seed, bool) or not (
            isinstance(self.seed, int) and 0 <= self.seed < SEED_LIMIT
        ):
            raise ValueError(
                f"GeneratedTrack.seed = {self.seed!r} is out of range: allowed [0, 2**63) "
                "(an integer)"
            )
        if not isinstance(self.spec, TrackSpec):
            raise TypeError(f"GeneratedTrack.spec must be a TrackSpec, got {self.spec!r}")

    @property
    def name(self) -> str:
        """The track's name: ``generated-<size>-<seed>``, plus a tag when the spec
        differs from the size's defaults."""
        changed = {k: v for k, v in self.spec.changes().items() if k != "size"}
        digest = zlib.crc32(repr(sorted(changed.items())).encode())  # the same in every process
        tag = f"-{digest:08x}" if changed else ""
        return f"generated-{self.spec.size}-{self.seed}{tag}"


def _pair(name: str, value: object) -> tuple[float, float]:
    items = tuple(value) if isinstance(value, tuple | list) else ()
    if len(items) != 2:
        raise ValueError(f"TrackSpec.{name} = {value!r}: expected a pair (low, high)")
    for v in items:
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise ValueError(f"TrackSpec.{name} = {value!r}: expected two finite numbers")
    return (items[0], items[1])


def _range(name: str, pair: tuple[float, float], lo: float, hi: float, unit: str) -> None:
    a, b = pair
    if not lo <= a <= b <= hi:
        units = f" [{unit}]" if unit else ""
        raise ValueError(
            f"TrackSpec.{name} = ({a:g}, {b:g}) is out of range: allowed "
            f"{lo:g} <= low <= high <= {hi:g}{units}"
        )


def _check(name: str, value: float, lo: float, hi: float, unit: str) -> None:
    if not (isinstance(value, int | float) and not isinstance(value, bool)):
        raise ValueError(f"TrackSpec.{name} = {value!r}: expected a number")
    if not (math.isfinite(value) and lo <= value <= hi):
        units = f" [{unit}]" if unit else ""
        raise ValueError(
            f"TrackSpec.{name} = {value!r} is out of range: allowed [{lo:g}, {hi:g}]{units}"
        )

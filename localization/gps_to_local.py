"""The ROS pipeline's ``gps_to_local_cartesian`` node: a GPS fix -> ``/local_xy`` in ``reference``.

Spec 000, "GPS to Local Cartesian Conversion": on each ``NavSatFix`` the node
computes the equirectangular projection about the reference origin
(``localization.geodesy.gps_to_local_cartesian``, R = 6378137 m)::

    x = (lon_r - ref_lon_r) * cos(ref_lat_r) * R_EARTH
    y = (lat_r - ref_lat_r) * R_EARTH

(the longitude difference taken the short way round across the antimeridian)
and publishes a ``PointStamped`` with the fix's stamp and z = 0. The ROS pipeline
copies the whole header; here the stamp is kept and ``frame_id`` is set to
``reference``, the frame the ROS pipeline says the point is in ("we treat this (x, y)
as coordinates in the reference frame"), so no consumer mistakes it for an
antenna-frame point.

The ROS pipeline publishes whatever it gets. :class:`GpsToLocalCartesian` drops fixes
that carry no position (status NO_FIX, NaN or infinite latitude/longitude),
counting and logging the reason, since a NaN ``/local_xy`` would poison every
consumer downstream.
"""

from __future__ import annotations

import logging
import math
from collections import Counter

from conesim.core.geodesy import (
    DEFAULT_ORIGIN,
    R_EARTH,
    GeodesyError,
    ReferenceOrigin,
    wrapped_lon_difference,
)
from conesim.core.geodesy import gps_to_local_cartesian as project
from conesim.core.messages import FRAME_REFERENCE, Header, NavSatFix, NavSatStatus, PointStamped

_log = logging.getLogger(__name__)


def gps_to_local_cartesian(
    fix: NavSatFix, origin: ReferenceOrigin = DEFAULT_ORIGIN, frame_id: str = FRAME_REFERENCE
) -> PointStamped:
    """Project one fix into ``reference``: the ROS pipeline's ``/local_xy``.

    Args:
        fix: the GPS fix (latitude, longitude [deg]); its status is not looked at.
        origin: the ``reference`` origin.
        frame_id: frame of the output point.

    Returns:
        The point (x east, y north [m], z = 0) stamped with ``fix.header.stamp``.

    Raises:
        GeodesyError: NaN, infinite or out-of-range latitude/longitude.
    """
    lat, lon = fix.latitude, fix.longitude
    if type(lat) is float and type(lon) is float and abs(lat) <= 90.0 and abs(lon) <= 180.0:
        # One fix on floats: ``project``'s arithmetic, operation for operation (numpy's
        # ``radians`` is the same single multiplication as ``math.radians``), without
        # its array overhead. NaN fails the range test and takes ``project``, which raises.
        ref_lat_r, ref_lon_r = math.radians(origin.lat_deg), math.radians(origin.lon_deg)
        x = wrapped_lon_difference(math.radians(lon) - ref_lon_r) * math.cos(ref_lat_r) * R_EARTH
        y = (math.radians(lat) - ref_lat_r) * R_EARTH
    else:
        xs, ys = project(lat, lon, origin)
        x, y = float(xs), float(ys)
    return PointStamped(Header(fix.header.stamp, frame_id), x, y, 0.0)


class GpsToLocalCartesian:
    """The node: fixes in, ``/local_xy`` points out, unusable fixes counted.

    Args:
        origin: the ``reference`` origin (the ROS pipeline's launch parameters).
        frame_id: frame of the output points.

    Attributes:
        dropped: fixes not converted, per reason: ``"no_fix"`` (status NO_FIX) or
            ``"invalid"`` (NaN/inf stamp, NaN/inf/out-of-range latitude or longitude).
    """

    def __init__(
        self, origin: ReferenceOrigin = DEFAULT_ORIGIN, frame_id: str = FRAME_REFERENCE
    ) -> None:
        self.origin = origin
        self.frame_id = frame_id
        self.dropped: Counter[str] = Counter()

    def __call__(self, fix: NavSatFix) -> PointStamped | None:
        """Convert one fix; None (counted and logged) if it has no usable position."""
        reason = None
        if fix.status == NavSatStatus.NO_FIX:
            reason = "no_fix"
        elif not math.isfinite(fix.header.stamp):
            reason = "invalid"
        if reason is None:
            try:
                return gps_to_local_cartesian(fix, self.origin, self.frame_id)
            except GeodesyError as err:
                reason = "invalid"
                _log.debug("gps_to_local_cartesian: %s", err)
        self.dropped[reason] += 1
        level = logging.WARNING if self.dropped[reason] == 1 else logging.DEBUG
        _log.log(
            level, "gps_to_local_cartesian dropped a fix at %r s: %s (%d so far)",
            fix.header.stamp, reason, self.dropped[reason],
        )  # fmt: skip
        return None

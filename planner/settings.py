"""The settings groups the compiled steps read, as named tuples.

numba takes a ``NamedTuple`` as one argument and reads its fields by name in
compiled code, so each kernel gets its group whole instead of a long run of
positional scalars. Each group is built once per settings object
(``MidlineConfig.view_settings`` ..., ``SpeedProfileConfig.limit_settings``,
``pass_settings``) by ``from_fields``, from the frozen dataclass of
``planner.config`` whose fields have the same names, with floats as
``float``, counts as ``int`` and switches as ``bool``: one type per field,
so one compiled specialisation per kernel.
"""

from __future__ import annotations

from typing import Any, NamedTuple, TypeVar, get_type_hints

_Group = TypeVar("_Group", bound=tuple[Any, ...])


def from_fields(group: type[_Group], source: object, **computed: Any) -> _Group:
    """The settings group ``group`` with ``source``'s attributes of the same names.

    Each field is ``source``'s attribute converted to the field's type
    (``float``, ``int`` or ``bool``), or, for a field ``source`` has not, the
    value given in ``computed``.

    Raises:
        AttributeError: a field neither ``source`` nor ``computed`` has.
    """
    types = get_type_hints(group)
    values = {
        name: computed[name] if name in computed else types[name](getattr(source, name))
        for name in types
    }
    return group(**values)


class ViewSettings(NamedTuple):
    """Step 2 (``kernels.boundary_cones``): the view, the pairing and the track estimate.

    Attributes:
        min_x: cones behind this x in ``os_sensor`` are out of view [m].
        max_range: cones farther than this are out of view [m].
        min_boundary_offset: nearer the global path a cone is no boundary cone [m].
        max_boundary_offset: farther from it neither [m].
        max_station_gap: largest station gap of a pair on one stretch of track [m].
        min_track_width: a pair's span (offset difference) is at least this [m] ...
        max_track_width: ... and at most this [m].
        max_bridge_length: a pair's cones are at most this far apart [m].
        min_width_samples: pairs needed to measure the width [-].
        nominal_track_width: the width when it is not measured [m].
        boundary_tolerance: a cone more than this inside its boundary line
            is dropped once the track is measured [m].
    """

    min_x: float
    max_range: float
    min_boundary_offset: float
    max_boundary_offset: float
    max_station_gap: float
    min_track_width: float
    max_track_width: float
    max_bridge_length: float
    min_width_samples: int
    nominal_track_width: float
    boundary_tolerance: float


class PartnerSettings(NamedTuple):
    """Step 3a (``kernels.partners_needed``): the virtual partners.

    Attributes:
        partner_radius: a cone with a cone of the other side this close has
            no virtual partner [m].
        partner_offset_tolerance: only a cone this close to its boundary line
            gets one [m].
    """

    partner_radius: float
    partner_offset_tolerance: float


class BridgeSettings(NamedTuple):
    """Step 3 (``kernels.find_bridges``, ``kernels.boundary_edges``): the bridges' checks.

    Attributes:
        min_track_width: a bridge spans at least this across the path [m];
            a same-side edge spanning less runs along a boundary.
        max_track_width: a bridge spans at most this [m].
        max_bridge_length: a bridge is at most this long [m].
        max_station_gap: both ends of a bridge or boundary edge lie within
            this station gap [m].
        width_tolerance: a bridge's span is within this of a measured width [m].
        shortest: keep only the bridges that are the shortest valid bridge
            of one of their cones (``bridge_selection == "shortest"``).
    """

    min_track_width: float
    max_track_width: float
    max_bridge_length: float
    max_station_gap: float
    width_tolerance: float
    shortest: bool


class OrderingSettings(NamedTuple):
    """Step 4 (``kernels.ordered_midpoints``): the start and the chain's guards.

    Attributes:
        start_min_x: the first midpoint lies ahead of this x [m].
        start_station_back: and at most this behind the sensor's station [m].
        start_station_ahead: and at most this ahead of it [m].
        max_step: longest step of the chain [m].
        max_station_step: largest station advance of a step [m].
        station_back_tolerance: largest station regression of a step [m].
        min_step_advance: a step advances along the track by at least this
            fraction of its length [-].
        min_midpoint_spacing: a midpoint this close to the chain's last one
            is merged into it [m].
    """

    start_min_x: float
    start_station_back: float
    start_station_ahead: float
    max_step: float
    max_station_step: float
    station_back_tolerance: float
    min_step_advance: float
    min_midpoint_spacing: float


class LimitSettings(NamedTuple):
    """Step 7's limits (``kernels.profile_limits``): curvature, its window, the jerk limit.

    Attributes:
        curvature_window: the curvature is averaged over this arc length [m]
            (0: point by point).
        a_lat_max: lateral acceleration limit at rest [m/s^2].
        a_lat_aero: its growth with speed squared [1/m].
        curvature_floor: ``a_lat_max / v_max**2``, below which ``v_max``
            binds [1/m].
        v_max: speed cap [m/s].
        lateral_jerk_max: lateral jerk limit [m/s^3]; inf: none.
        jerk_window: the curvature's slope is taken over this arc length [m].
        lock_radius: the car's full-lock turning radius [m]; the lateral
            limit shrinks towards it (0: never).
        lock_share_min: the least share of the lateral limit left there [-].
        steering_rate_max: the steering-rate limit [rad/s]; inf: none.
        steering_weight_min: the least weight of the steering-rate limit,
            away from full lock [-].
        wheelbase: the car's wheelbase L [m], for it.
    """

    curvature_window: float
    a_lat_max: float
    a_lat_aero: float
    curvature_floor: float
    v_max: float
    lateral_jerk_max: float
    jerk_window: float
    lock_radius: float
    lock_share_min: float
    steering_rate_max: float
    steering_weight_min: float
    wheelbase: float


class PassSettings(NamedTuple):
    """Step 7's passes (``kernels.profile_passes``): drive, horizon stop and brake.

    Attributes:
        friction_ellipse: the passes use only the grip the corner leaves.
        a_drive: acceleration limit of the drive pass [m/s^2].
        a_brake: deceleration limit of the brake pass [m/s^2], > 0.
        a_lat_max: lateral acceleration limit at rest [m/s^2] (the ellipse's).
        a_lat_aero: its growth with speed squared [1/m].
        horizon_stop: the last waypoint's speed is 0 (or the given end speed).
        brake: the brake pass runs (False: the drive pass alone, for
            ``speed_profile.forward_pass``).
        brake_lateral_share: the brake pass's ellipse takes this share of
            the lateral limit as its whole [-] (1: the same ellipse).
        drive_lateral_share: the drive pass's ellipse takes this share of
            the lateral limit as its whole [-] (1: the same ellipse).
    """

    friction_ellipse: bool
    a_drive: float
    a_brake: float
    a_lat_max: float
    a_lat_aero: float
    horizon_stop: bool
    brake: bool
    brake_lateral_share: float = 1.0
    drive_lateral_share: float = 1.0


class LaneSettings(NamedTuple):
    """Step 5b (``kernels.lane_room``, ``kernels.lane_path``): the body in the lane.

    Attributes:
        body_half_width: half the car's width [m].
        body_front: the car's front end ahead of the rear axle [m] (its
            sweep outside a turn).
        clearance: what the body keeps from a boundary line [m] (cone radius
            and tracking error).
        iterations: the elastic band's sweeps (0: the path as fitted).
    """

    body_half_width: float
    body_front: float
    clearance: float
    iterations: int

"""The ``conesim`` command line.

Subcommands:

* ``conesim tracks``: the shipped tracks with length, cone counts and width range.
* ``conesim track show NAME|PATH --out FILE.png``: a picture of the cones by kind
  and the global path coloured by covariance status.
* ``conesim track check NAME|PATH [--json]``: the Formula Student validator.
* ``conesim track generate --seed S --out FILE [--size ...]``: a random
  FS-rule track (``tracks.generate``), written in the conesim format.
* ``conesim run [SCENARIO.yaml] [--set KEY=VALUE ...] [flags]``: one
  headless closed-loop scenario (``envs.runner``): a results table,
  ``DIR/result.json`` and ``DIR/run.png``; with ``--bag BAG`` also a ROS 2
  bag of the run (``envs.bag``). The scenario is the file's
  (``envs.scenario_file``), changed by each ``--set``, then by the flags
  (``--track``, ``--laps``, ``--seed``, ``--sensors``, ``--localization``).
  A track in which ``track check`` finds errors is bad input for ``run``
  (warnings are not). ``--out`` must be new, empty or a previous run's
  (``envs.run_dir``).
* ``conesim scenario show [SCENARIO.yaml] [--set ...] [flags]``: the scenario
  ``run`` would run, as YAML with every default filled in.
* ``conesim sweep SWEEP.yaml --out DIR [--workers N] [--ray [ADDRESS]]`` and
  ``conesim sweep summary DIR``: many runs (``envs.cli_sweep``).

``-v`` (log the nodes' warnings) goes before or after the subcommand.

Exit codes: 0 success (``run``: every lap completed), 1 a check found errors
or a run did not finish (off track, stuck, time limit), 2 bad input (one line
on stderr per problem, naming the file or option and what is wrong; never a
traceback; nothing written; argparse's errors too), 130 interrupted (Ctrl-C:
one line; ``run`` writes nothing, ``sweep`` keeps the runs finished), 141
the reader of stdout went away (a pipe into ``head``), quietly, as a shell
reports a command ended by SIGPIPE.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import math
import os
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from gymnasium.error import DependencyNotInstalled

from conesim.core.geodesy import GeodesyError
from conesim.envs.cli_parser import CliError, build_parser
from conesim.envs.dataclass_io import FieldError
from conesim.envs.paths import missing_dirs, nearest_existing, os_reason, probe_writable
from conesim.envs.progress import ProgressBar
from conesim.envs.run_dir import RunDirError, check_run_dir, write_together
from conesim.envs.run_plot import save_run_picture
from conesim.envs.track_plot import save_track_picture
from conesim.envs.yaml_io import parse_value
from conesim.tracks import (
    DEFAULT_TRACK,
    Layout,
    Track,
    TrackFormatError,
    TrackNotFoundError,
    TrackSource,
    TrackSpec,
    check_report,
    generate_track,
    load_track,
    shipped_tracks,
    track_label,
    write_track,
)
from conesim.tracks.generate.spec import SEED_LIMIT
from conesim.tracks.global_path import (
    GlobalPath,
    GlobalPathError,
    global_path_for_track,
)

if TYPE_CHECKING:
    from conesim.envs.runner import RunResult
    from conesim.envs.scenario import Scenario
    from conesim.envs.scenario_file import Override

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE: what a shell reports for a reader that went away
EXIT_INTERRUPTED = 130  # 128 + SIGINT: Ctrl-C

INPUT_ERRORS = (TrackFormatError, GlobalPathError, GeodesyError, FileNotFoundError, FieldError)
__all__ = ["EXIT_BAD_INPUT", "CliError", "build_parser", "main"]


def cmd_tracks() -> int:
    """Print the shipped tracks as a table."""
    header = f"{'track':<14}{'layout':<10}{'length [m]':>11}{'cones':>7}{'width [m]':>14}"
    print(header)
    print("-" * len(header))
    for name in shipped_tracks():
        track = load_track(name)
        report = check_report(track)
        width = f"{report['width_min_m']:.2f}-{report['width_max_m']:.2f}"
        mark = " (default)" if name == DEFAULT_TRACK else ""
        print(
            f"{name:<14}{track.layout:<10}{report['length_m']:>11.1f}"
            f"{len(track.cones):>7}{width:>14}{mark}"
        )
    return EXIT_OK


def _load_track(name: TrackSource, option: str) -> Track:
    """``load_track`` that refuses an empty name (which would read the current directory);
    a track it cannot find is said with ``option``, where it was given."""
    if not track_label(name).strip():
        raise CliError(f"{option}: empty track name; give a shipped track name or a track file")
    try:
        return load_track(name)
    except TrackNotFoundError as exc:
        raise CliError(f"{option}: {exc}") from None


def _track_option(args: argparse.Namespace) -> str:
    """Where the run's track was given, for its errors: the flag, the last ``--set`` of
    it, the scenario file (a relative file is beside it), or the default."""
    if args.track is not None:
        return f"--track {args.track}"
    sets = [item for item in args.set or () if item.partition("=")[0].strip() == "track"]
    if sets:
        return f"--set {sets[-1]}"
    if args.scenario is not None:
        return f"{args.scenario}: track (a file is looked for beside the scenario file)"
    return "track"


def cmd_track_show(name: str, out: str) -> int:
    """Draw a track and its global path to a PNG."""
    if not out.strip():
        raise CliError("--out: empty file name; give a .png file name")
    if not out.lower().endswith(".png"):
        raise CliError(f"--out {out}: the picture is written as PNG, give a .png file name")
    target = Path(out)
    try:
        if target.is_dir():
            raise CliError(f"--out {out}: is a directory; give a .png file name")
        base = nearest_existing(target.parent)
    except OSError as exc:
        raise CliError(f"--out {out}: cannot write there ({os_reason(exc)})") from None
    if not base.is_dir():
        raise CliError(f"--out {out}: {base} is not a directory")
    track = _load_track(name, "track")
    path = global_path_for_track(track)
    try:
        written = save_track_picture(track, path, target)
    except OSError as exc:
        raise CliError(f"--out {out}: cannot write the picture ({os_reason(exc)})") from None
    red = int(path.high_covariance.sum())
    print(
        f"wrote {written}: {track.name}, {len(track.cones)} cones, global path "
        f"{path.polyline.length:.1f} m with {red} of {len(path.cov)} points above "
        f"cov {path.cov_threshold:g} m^2 (red)"
    )
    return EXIT_OK


def cmd_track_check(name: str, as_json: bool) -> int:
    """Validate a track; exit 0 when it has no errors.

    A track that cannot be read (or a malformed global path CSV) is bad input:
    exit 2 and one line on stderr; with ``--json`` its lines are also printed
    on stdout as ``{"track": ..., "input_error": true, "errors": [...]}``, so a
    script reading stdout gets JSON either way.
    """
    try:
        track = _load_track(name, "track")
        report = check_report(track)
    except (*INPUT_ERRORS, CliError) as exc:
        if as_json:
            lines = str(exc).splitlines() or [""]
            print(json.dumps({"track": name, "input_error": True, "errors": lines}))
        raise
    if as_json:
        print(json.dumps(report))
    else:
        cones = ", ".join(f"{k} {n}" for k, n in report["cones"].items())
        print(f"{track.name}: {report['length_m']:.1f} m, {cones}")
        print(f"width {report['width_min_m']:.2f}-{report['width_max_m']:.2f} m")
        for warning in report["warnings"]:
            print(f"warning: {warning}")
        for error in report["errors"]:
            print(f"error: {error}")
        if not report["warnings"] and not report["errors"]:
            print("ok: no warnings, no errors")
    return EXIT_FAILED if report["errors"] else EXIT_OK


GENERATE_FLAGS = {
    "size": "size",
    "length": "length",
    "width": "width",
    "hairpins": "hairpins",
    "tight_share": "tight_share",
    "min_radius": "min_radius",
    "gate_offset": "gate_offset",
}
"""``track generate``'s flags and the ``TrackSpec`` field each sets."""


def cmd_track_generate(args: argparse.Namespace) -> int:
    """Generate a track, write it, and print what it is and what ``track check`` finds."""
    out = args.out
    if not out.strip():
        raise CliError("--out: empty file name; give a .yaml file name")
    target = Path(out)
    if target.is_dir():
        raise CliError(f"--out {out}: is a directory; give a .yaml file name")
    if target.suffix not in (".yaml", ".yml"):
        raise CliError(f"--out {out}: a conesim track file ends in .yaml")
    if not 0 <= args.seed < SEED_LIMIT:
        raise CliError(f"--seed {args.seed}: must be a non-negative integer below 2**63")
    given = {field: getattr(args, flag) for flag, field in GENERATE_FLAGS.items()}
    try:
        spec = TrackSpec(**{k: v for k, v in given.items() if v is not None})
    except ValueError as exc:
        named = [f for f, field in GENERATE_FLAGS.items() if f"TrackSpec.{field} " in str(exc)]
        flag = f"--{named[0].replace('_', '-')}: " if named else ""
        raise CliError(f"{flag}{exc}") from None
    track = generate_track(args.seed, spec)
    try:
        written = write_track(track, target)
    except OSError as exc:
        raise CliError(f"--out {out}: cannot write the track ({os_reason(exc)})") from None
    report = check_report(track)
    print(
        f"wrote {written}: {track.name}, {report['length_m']:.1f} m, width "
        f"{report['width_min_m']:.2f}-{report['width_max_m']:.2f} m, {len(track.cones)} cones"
    )
    print(track.description)
    for warning in report["warnings"]:
        print(f"warning: {warning}")
    for error in report["errors"]:
        print(f"error: {error}")
    return EXIT_FAILED if report["errors"] else EXIT_OK


FLAGS = {
    "track": "track",
    "laps": "laps",
    "seed": "seed",
    "sensors": "sensors.profile",
    "localization": "localization",
}
"""``run``'s flags and the scenario key each sets."""


def _overrides(args: argparse.Namespace) -> list[Override]:
    """The ``--set`` changes, in order, then the flags' (which win)."""
    from conesim.envs.scenario_file import Override  # noqa: PLC0415 (with the loop: cmd_run)

    out = []
    for item in args.set:
        key, eq, text = item.partition("=")
        if not eq or not key.strip():
            raise CliError(f"--set {item}: expected KEY=VALUE, e.g. --set laps=2")
        try:
            value = parse_value(text)
        except FieldError as exc:
            raise CliError(f"--set {item}: {exc.reason}") from None
        out.append(Override(key.strip(), value, f"--set {item}"))
    for flag, key in FLAGS.items():
        value = getattr(args, flag)
        if value is not None:
            out.append(Override(key, value, f"--{flag} {value}"))
    return out


def _scenario(args: argparse.Namespace) -> Scenario:
    """The scenario of the arguments: the file's, then ``--set``, then the flags.

    The flags' own ranges are checked first, so that their errors name them.
    """
    from conesim.envs.scenario import MAX_LAPS  # noqa: PLC0415 (with the loop)
    from conesim.envs.scenario_file import load_scenario  # noqa: PLC0415 (with the loop)

    if args.laps is not None and not 1 <= args.laps <= MAX_LAPS:
        raise CliError(f"--laps {args.laps}: must be in [1, {MAX_LAPS}]")
    if args.seed is not None and not 0 <= args.seed < SEED_LIMIT:
        raise CliError(f"--seed {args.seed}: must be a non-negative integer below 2**63")
    if args.track is not None and not args.track.strip():
        raise CliError("--track: empty track name; give a shipped track name or a track file")
    if args.scenario is not None and not args.scenario.strip():
        raise CliError("empty scenario file name; give a .yaml file, or none for the defaults")
    return load_scenario(args.scenario, _overrides(args))


def cmd_scenario_show(args: argparse.Namespace) -> int:
    """Print the scenario ``run`` would run, every default filled in, as YAML.

    The track is read too, so a scenario that shows is one that runs.
    """
    from conesim.envs.scenario_file import scenario_yaml  # noqa: PLC0415 (with the loop)

    scenario = _scenario(args)
    _load_track(scenario.track, _track_option(args))
    sys.stdout.write(scenario_yaml(scenario))
    return EXIT_OK


def cmd_run(args: argparse.Namespace) -> int:
    """Run one scenario; write result.json and run.png; print the results.

    Every input is checked before the run (the scenario file and its
    overrides, the track, including the validator that ``track check``
    runs, the output directory, the render extra, the bag directory and the
    ros extra), so bad input costs no simulation and writes nothing; the
    output directory is created only once the results exist, and the two
    outputs are written to temporary files and moved into place together.
    The bag is written beside its target and moved into place at the end of
    the run; it is removed again if the two outputs cannot be written.
    """
    # The closed loop (and its compiled kernels) loads only here: `tracks`,
    # `track check` and `--help` neither pay for it nor print its warnings.
    from conesim.envs.runner import run_scenario  # noqa: PLC0415

    if not args.out.strip():
        raise CliError("--out: empty directory name; give the output directory")
    if args.bag is not None:  # first: an empty name is the working directory, --out's parent
        from conesim.envs.bag import check_bag_target  # noqa: PLC0415 (with the loop: cmd_run)

        with _bag_errors():
            check_bag_target(args.bag)
    scenario = _scenario(args)
    track = _load_track(scenario.track, _track_option(args))
    global_path = global_path_for_track(track)
    errors = check_report(track)["errors"]
    if errors:
        raise CliError("\n".join(f"{scenario.track_name}: {error}" for error in errors))
    out = Path(args.out)
    try:
        check_run_dir(
            out,
            scenario=None if args.scenario is None else Path(args.scenario),
            bag=None if args.bag is None else Path(args.bag),
        )
    except RunDirError as exc:
        raise CliError(f"--out {exc}") from None
    if args.render:
        _check_render_extra()
    save_map = _check_save_map(args.save_map, scenario, track)
    bar = ProgressBar(sys.stderr) if sys.stderr.isatty() and not args.json else None
    # What is the user's already, for removing the bag again: an empty
    # directory they made stays, parents made for the bag go.
    bag_existed, bag_parents = False, []
    if args.bag is not None:
        bag_path = Path(os.path.abspath(args.bag))
        bag_existed, bag_parents = bag_path.is_dir(), missing_dirs(bag_path.parent)
    with _bag_errors():
        result = run_scenario(
            scenario, render=args.render, progress=bar.update if bar else None, bag=args.bag
        )
    if bar:
        bar.close()
    payload = json.dumps(result.to_json(), indent=2)
    try:
        _write_outputs(out, payload, result, track, global_path)
    except CliError:
        if args.bag is not None:  # the bag without its results would be half a run
            from conesim.envs.bag import remove_bag  # noqa: PLC0415 (with the loop: cmd_run)

            remove_bag(args.bag, bag_existed, bag_parents)
        raise
    if save_map is not None:
        _write_map(save_map, result, track)
    if args.json:
        print(payload)
    else:
        print(format_result(result, out, args.bag, args.scenario, save_map))
    return EXIT_OK if result.finished else EXIT_FAILED


def _check_save_map(path: str | None, scenario: Scenario, track: Track) -> Path | None:
    """``--save-map``'s file, checked before the run: slam only, not on a skidpad, a
    .yaml file (not a directory) whose nearest existing folder can be written."""
    if path is None:
        return None
    if scenario.localization != "slam":
        raise CliError(
            f"--save-map needs --localization slam (the scenario's is {scenario.localization!r})"
        )
    if track.layout == Layout.SKIDPAD:
        raise CliError(
            "--save-map: a skidpad's map after its first lap holds one of its two circles, "
            "which no skidpad track file can be; map a loop or a lane"
        )
    target = Path(path)
    if target.suffix not in (".yaml", ".yml"):
        raise CliError(f"--save-map {path}: a conesim track file ends in .yaml")
    if target.is_dir():
        raise CliError(f"--save-map {path}: is a directory")
    base = nearest_existing(target.parent)
    if not base.is_dir():
        raise CliError(f"--save-map {path}: {base} is not a directory")
    try:
        probe_writable(base)
    except OSError as exc:
        raise CliError(f"--save-map {path}: cannot write there ({os_reason(exc)})") from None
    return target


def _write_map(path: Path, result: RunResult, track: Track) -> None:
    """Write the run's map (after lap 1, else at the end) as a conesim track file."""
    from conesim.envs.map_quality import map_track  # noqa: PLC0415 (with the loop: cmd_run)

    snap = result.slam_map
    if snap is None or not len(snap.positions):
        raise CliError("--save-map: the run built no map (the filter never initialised)")
    try:
        write_track(map_track(snap, track), path)
    except OSError as exc:
        raise CliError(f"--save-map {path}: cannot write the map ({os_reason(exc)})") from None


@contextlib.contextmanager
def _bag_errors() -> Iterator[None]:
    """``--bag``'s problems as one line each: the path, or the missing extra."""
    from conesim.envs.bag import BagError  # noqa: PLC0415 (with the loop: cmd_run)

    try:
        yield
    except BagError as exc:
        raise CliError(f"--bag {exc}") from None
    except DependencyNotInstalled as exc:
        raise CliError(f"--bag: {exc}") from None


def _check_render_extra() -> None:
    from conesim.envs.render import window_problem  # noqa: PLC0415 (with the loop: cmd_run)

    problem = window_problem()
    if problem is not None:
        raise CliError(f"--render: {problem}")


def _write_outputs(
    out: Path, payload: str, result: RunResult, track: Track, global_path: GlobalPath
) -> None:
    """Write run.png and result.json into ``out``: both, or nothing (``write_together``)."""
    try:
        write_together(
            out,
            {
                "run.png": lambda path: save_run_picture(result, track, global_path, path),
                "result.json": lambda path: path.write_text(payload + "\n", encoding="utf-8"),
            },
        )
    except OSError as exc:
        raise CliError(f"--out {out}: cannot write the results ({os_reason(exc)})") from None


def format_result(
    result: RunResult,
    out: Path,
    bag: str | None = None,
    scenario: str | None = None,
    saved_map: Path | None = None,
) -> str:
    """The results table ``conesim run`` prints (``bag``: the bag written, if any;
    ``scenario``: the scenario file run, if any; ``saved_map``: ``--save-map``'s file)."""

    def num(value: float | None, fmt: str, unit: str) -> str:
        return "n/a" if value is None else f"{format(value, fmt)} {unit}"

    laps = ", ".join(f"{t:.2f} s" for t in result.lap_times_s) or "none"
    written = [str(out / "result.json"), str(out / "run.png")]
    written += [str(extra) for extra in (bag, saved_map) if extra is not None]
    ratio = result.lap_time_ratio
    best = "n/a" if ratio is None or not math.isfinite(ratio) else f"{ratio:.2f}x"
    rows = [] if scenario is None else [("scenario", scenario)]
    rows += [
        (
            "track",
            f"{result.track} ({result.sensors} sensors, {result.localization} "
            f"localization, seed {result.seed})",
        ),
        ("finished", f"{'yes' if result.finished else 'no'} ({result.end_reason})"),
        ("laps", f"{result.laps_completed}/{result.laps}: {laps}"),
        (
            "limit lap",
            f"{result.limit_lap_time_s:.2f} s (best lap {best}); "
            f"centreline {result.centreline_lap_time_s:.2f} s",
        ),
        ("cones hit / DOO", f"{result.cones_hit} / {result.cones_down_or_out}"),
        ("off-track events", str(result.off_track_events)),
        (
            "localization RMSE",
            f"{num(result.localization_pos_rmse_m, '.3f', 'm')}, "
            f"{num(result.localization_yaw_rmse_deg, '.3f', 'deg')}",
        ),
        ("midline RMSE", num(result.midline_rmse_m, ".3f", "m")),
        ("planner fallbacks", str(result.planner_fallbacks)),
        *_map_rows(result),
        (
            "sim / wall time",
            f"{result.sim_time_s:.2f} s / {result.wall_time_s:.2f} s "
            f"({result.real_time_factor:.1f}x real time; setup {result.setup_time_s:.2f} s)",
        ),
        ("written", ", ".join(written)),
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _map_rows(result: RunResult) -> list[tuple[str, str]]:
    """The map's rows of the results table (``slam`` localization), else none."""
    q = result.map_quality
    if q is None:
        return []
    lap = result.map_quality_lap
    when = f"after lap {lap}" if lap else "at the end"
    return [
        (
            "map " + when,
            f"{q['landmarks']} landmarks for {q['cones']} cones, {q['missed']} missed, "
            f"{q['spurious']} spurious; error {q['mean_error_m']:.3f} m mean, "
            f"{q['mean_error_aligned_m']:.3f} m with the best rigid fit removed",
        )
    ]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``conesim`` console script."""
    try:
        args = build_parser().parse_args(argv)
        logging.basicConfig(
            level=logging.WARNING if args.verbose else logging.ERROR,
            format="conesim: %(name)s: %(message)s",
        )
        if args.command == "tracks":
            return cmd_tracks()
        if args.command == "track" and args.track_command == "show":
            return cmd_track_show(args.track, args.out)
        if args.command == "track" and args.track_command == "check":
            return cmd_track_check(args.track, args.json)
        if args.command == "track" and args.track_command == "generate":
            return cmd_track_generate(args)
        if args.command == "run":
            return cmd_run(args)
        if args.command == "scenario" and args.scenario_command == "show":
            return cmd_scenario_show(args)
        if args.command == "sweep":
            from conesim.envs.cli_sweep import cmd_sweep  # noqa: PLC0415 (with the loop)

            return cmd_sweep(args)
    except (*INPUT_ERRORS, CliError) as exc:
        for line in str(exc).splitlines() or [""]:
            print(f"conesim: error: {line}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        # Ctrl-C: one line, not a traceback. ``run`` writes its outputs only at
        # the end (a bag's temporary directory is removed on the way out);
        # ``sweep`` catches it itself and says what it kept.
        print("conesim: interrupted; nothing written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        # The reader went away (`conesim tracks | head -1`): stop quietly, as
        # a command in a pipeline should. What is left for stdout, Python's
        # own flush at exit included, goes to the null device, not a traceback.
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)
        return EXIT_BROKEN_PIPE
    raise AssertionError(f"unhandled command {args.command!r}")  # argparse prevents this


if __name__ == "__main__":
    sys.exit(main())

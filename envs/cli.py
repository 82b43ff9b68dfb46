"""The ``conesim`` command line.

Subcommands:

* ``conesim tracks``: the shipped tracks with length, cone counts and width range.
* ``conesim track show NAME|PATH --out FILE.png``: a picture of the cones by kind
  and the global path coloured by covariance status.
* ``conesim track check NAME|PATH [--json]``: the Formula Student validator.

Exit codes: 0 success, 1 a check found errors, 2 bad input (one line on stderr
naming the file and what is wrong; never a traceback).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

from envs.track_plot import save_track_picture
from localization.geodesy import GeodesyError
from localization.global_path import GlobalPathError, global_path_for_track
from tracks import DEFAULT_TRACK, TrackFormatError, check_report, load_track, shipped_tracks

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2

INPUT_ERRORS = (TrackFormatError, GlobalPathError, GeodesyError, FileNotFoundError)


class CliError(Exception):
    """Bad input found by the command line itself."""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser for every subcommand."""
    parser = argparse.ArgumentParser(
        prog="conesim",
        description="Closed-loop 2D simulator for Formula Student cone tracks.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    sub.add_parser("tracks", help="list the shipped tracks with length, cones and width range")

    track = sub.add_parser("track", help="inspect one track (shipped name or file)")
    track_sub = track.add_subparsers(dest="track_command", required=True, metavar="ACTION")
    show = track_sub.add_parser("show", help="draw cones and global path to a PNG")
    show.add_argument("track", help="shipped track name or a track file (conesim/fssim/EUFS/FSDS)")
    show.add_argument("--out", required=True, help="output PNG file")
    check = track_sub.add_parser("check", help="validate against Formula Student rules")
    check.add_argument("track", help="shipped track name or a track file")
    check.add_argument("--json", action="store_true", help="print one JSON object")
    return parser


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


def cmd_track_show(name: str, out: str) -> int:
    """Draw a track and its global path to a PNG."""
    if not out.lower().endswith(".png"):
        raise CliError(f"--out {out}: the picture is written as PNG, give a .png file name")
    track = load_track(name)
    path = global_path_for_track(track)
    written = save_track_picture(track, path, out)
    red = int(path.high_covariance.sum())
    print(
        f"wrote {written}: {track.name}, {len(track.cones)} cones, global path "
        f"{path.length_m:.1f} m with {red} of {len(path.cov)} points above "
        f"cov {path.cov_threshold:g} m^2 (red)"
    )
    return EXIT_OK


def cmd_track_check(name: str, as_json: bool) -> int:
    """Validate a track; exit 0 when it has no errors."""
    track = load_track(name)
    report = check_report(track)
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


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``conesim`` console script."""
    args = build_parser().parse_args(argv)
    try:
        if args.command == "tracks":
            return cmd_tracks()
        if args.command == "track" and args.track_command == "show":
            return cmd_track_show(args.track, args.out)
        if args.command == "track" and args.track_command == "check":
            return cmd_track_check(args.track, args.json)
    except (*INPUT_ERRORS, CliError) as exc:
        print(f"conesim: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    raise AssertionError(f"unhandled command {args.command!r}")  # argparse prevents this


if __name__ == "__main__":
    sys.exit(main())

"""The ``conesim`` command's argument parser, whose errors are one line.

argparse prints its usage and exits on a bad argument (five lines for
``--seed abc``); here every parser of the command raises ``CliError``
instead, so that the command says one line, ``conesim: error: ...``, and
exits 2, as it does for every other bad input. The parser imports nothing
heavy: ``conesim tracks`` and ``--help`` stay fast.
"""

from __future__ import annotations

import argparse
from typing import NoReturn, get_args

from conesim.localization.modes import LOCALIZATION_MODES
from conesim.sim.sensors import PROFILES as SENSOR_PROFILES
from conesim.tracks.generate.spec import Size

VERBOSE_HELP = "log the nodes' warnings (rejected messages)"


class CliError(Exception):
    """Bad input found by the command line itself (one line per problem)."""


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors raise ``CliError`` (one line) instead of exiting."""

    def error(self, message: str) -> NoReturn:
        """Raise the problem as one line that points at the subcommand's help."""
        raise CliError(f"{message} (see '{self.prog} --help')")


def _scenario_options(parser: argparse.ArgumentParser) -> None:
    """What makes a scenario: a file, dotted overrides, and the flags that override both."""
    parser.add_argument(
        "scenario", nargs="?", metavar="SCENARIO.yaml", help="a scenario file (README: Scenarios)"
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="change one dotted key of the scenario, e.g. --set faults.cones."
        "detection_probability=0.7 (repeatable; the value is YAML)",
    )
    parser.add_argument("--track", help="shipped track name or a track file (default trackdrive)")
    parser.add_argument("--laps", type=int, help="laps to drive (default 1)")
    parser.add_argument("--seed", type=int, help="episode seed (default 0)")
    parser.add_argument("--sensors", choices=list(SENSOR_PROFILES), help="sensor profile (rtk)")
    parser.add_argument(
        "--localization", choices=list(LOCALIZATION_MODES), help="localization mode (fused)"
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser for every subcommand."""
    parser = OneLineParser(
        prog="conesim",
        description="Closed-loop 2D simulator for Formula Student cone tracks.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help=VERBOSE_HELP)
    # -v after the subcommand too; SUPPRESS keeps a -v given before it.
    verbose = OneLineParser(add_help=False)
    verbose.add_argument(
        "-v", "--verbose", action="store_true", default=argparse.SUPPRESS, help=VERBOSE_HELP
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    sub.add_parser(
        "tracks",
        parents=[verbose],
        help="list the shipped tracks with length, cones and width range",
    )

    track = sub.add_parser(
        "track", parents=[verbose], help="inspect one track (shipped name or file)"
    )
    track_sub = track.add_subparsers(dest="track_command", required=True, metavar="ACTION")
    show = track_sub.add_parser(
        "show", parents=[verbose], help="draw cones and global path to a PNG"
    )
    show.add_argument("track", help="shipped track name or a track file (conesim/fssim/EUFS/FSDS)")
    show.add_argument("--out", required=True, help="output PNG file")
    check = track_sub.add_parser(
        "check", parents=[verbose], help="validate against Formula Student rules"
    )
    check.add_argument("track", help="shipped track name or a track file")
    check.add_argument("--json", action="store_true", help="print one JSON object")
    generate = track_sub.add_parser(
        "generate",
        parents=[verbose],
        help="generate a random FS-rule track and write it as a conesim track file",
        description="Generate a random closed FS-rule track (the same seed and settings "
        "give the same cones, always) and write it in the conesim format.",
    )
    generate.add_argument("--seed", type=int, required=True, help="the generator's seed")
    generate.add_argument("--out", required=True, help="the track file to write (.yaml)")
    generate.add_argument(
        "--size", choices=list(get_args(Size)), default="medium",
        help="lap length 200-280 m (small), 280-380 m (medium, default), 380-500 m (large)",
    )  # fmt: skip
    generate.add_argument(
        "--length", type=float, nargs=2, metavar=("MIN", "MAX"), help="lap length range [m]"
    )
    generate.add_argument(
        "--width", type=float, nargs=2, metavar=("MIN", "MAX"),
        help="lane width range [m] (default 3.0 3.5; FS: >= 3 m)",
    )  # fmt: skip
    generate.add_argument(
        "--hairpins", type=int, nargs=2, metavar=("MIN", "MAX"), help="how many hairpins"
    )
    generate.add_argument(
        "--tight-share", type=float,
        help="share of hairpins tighter than 4.5 m lane-centre radius, down to --min-radius "
        "(default 0.25)",
    )  # fmt: skip
    generate.add_argument(
        "--min-radius", type=float, help="tightest lane-centre radius [m] (default 3.0)"
    )
    generate.add_argument(
        "--gate-offset", type=float, nargs=2, metavar=("MIN", "MAX"),
        help="how far the big orange gate cones stand outside the lane [m] (default 0.5 1.2)",
    )  # fmt: skip

    run = sub.add_parser(
        "run",
        parents=[verbose],
        help="run one headless closed-loop scenario with the autopilot",
        description="Run a scenario: a file, changed by --set, then by the flags.",
    )
    _scenario_options(run)
    run.add_argument(
        "--out",
        default="runs/latest",
        help="output directory: new, empty, or a previous run's (default runs/latest)",
    )
    run.add_argument("--render", action="store_true", help="show a window (render extra)")
    run.add_argument("--json", action="store_true", help="print result.json to stdout")
    run.add_argument(
        "--bag",
        metavar="DIR",
        help="also record the run as a ROS 2 bag (rosbag2, MCAP) in the new directory DIR "
        "(ros extra)",
    )
    run.add_argument(
        "--save-map",
        metavar="FILE",
        help="with --localization slam: write the map after the first lap as a conesim "
        "track file (.yaml) that --track can load (not on the skidpad)",
    )

    _sweep_options(
        sub.add_parser(
            "sweep",
            parents=[verbose],
            help="run many scenarios: a base scenario and the axes to vary",
            description="Run a sweep: a base scenario and the axes to vary (their product, or\n"
            "a list of points), every run checked before the first starts (README: Sweeps).",
            epilog=SWEEP_EPILOG,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
    )

    scenario = sub.add_parser(
        "scenario", parents=[verbose], help="inspect a scenario (the settings of a run)"
    )
    scenario_sub = scenario.add_subparsers(dest="scenario_command", required=True, metavar="ACTION")
    show_scenario = scenario_sub.add_parser(
        "show",
        parents=[verbose],
        help="print the scenario as YAML with every default filled in",
        description="Print the scenario `conesim run` would run with the same arguments, "
        "every default filled in: saved, it runs the same run again.",
    )
    _scenario_options(show_scenario)
    return parser


SWEEP_EPILOG = """\
conesim sweep summary DIR writes DIR's summary.md, summary.png and failed.md
again from its results.jsonl (and prints the tables).

Outputs in DIR: results.jsonl (a row per run, written as each finishes),
runs/<run-id>/result.json and run.png (or error.txt), sweep.json, and at the
end summary.md, summary.png and failed.md. The same command again resumes an
interrupted sweep, skipping the runs done. Exit status: 0 every run clean,
1 some run not clean or an error, 2 bad input, 130 interrupted (Ctrl-C)."""


def _sweep_options(sweep: argparse.ArgumentParser) -> None:
    """``conesim sweep SWEEP.yaml --out DIR`` and ``conesim sweep summary DIR``."""
    sweep.add_argument(
        "sweep", metavar="SWEEP.yaml", help="the sweep file (or 'summary', then DIR)"
    )
    sweep.add_argument(
        "dir", nargs="?", metavar="DIR", help="with 'summary': the sweep's directory"
    )
    sweep.add_argument(
        "--out", metavar="DIR", help="output directory: new, empty, or this sweep's (resumes it)"
    )
    sweep.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="runs at once (default every core; 1 runs them in this process); "
        "with --ray the local Ray's CPUs",
    )
    sweep.add_argument(
        "--ray",
        nargs="?",
        const="local",
        metavar="ADDRESS",
        help="run on Ray: a local Ray started for the sweep, or the cluster at ADDRESS (ray extra)",
    )
    sweep.add_argument(
        "--pictures",
        choices=("all", "failed", "none"),
        default="all",
        help="which runs get a run.png: all (default), failed (not clean) or none; drawing "
        "one takes longer than a short run",
    )

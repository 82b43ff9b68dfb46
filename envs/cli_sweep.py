"""``conesim sweep``: many runs from a sweep file, and their summary.

* ``conesim sweep SWEEP.yaml --out DIR [--workers N] [--ray [ADDRESS]]``:
  the sweep file is loaded and every run's scenario and track checked
  (``envs.sweep_file``), ``DIR`` checked (``envs.sweep_store``) and the Ray
  extra found when asked for, all before the first run: bad input is one
  line, exit 2, nothing written. Then ``envs.sweep.run_sweep`` runs what
  ``DIR`` does not hold yet, with the progress on stderr, and the summary
  is printed.
* ``conesim sweep summary DIR``: the summary written again from ``DIR``.

Exit codes: 0 every run clean, 1 a run not clean or an error, 2 bad input,
130 interrupted (the runs finished are kept; the same command resumes).
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

from conesim.envs.cli_parser import CliError
from conesim.envs.paths import os_reason

EXIT_OK, EXIT_FAILED, EXIT_INTERRUPTED = 0, 1, 130
MAX_WORKERS = 1024


def cmd_sweep(args: argparse.Namespace) -> int:
    """``conesim sweep`` (see the module docstring)."""
    if args.sweep == "summary":
        return cmd_sweep_summary(args)
    if args.dir is not None:
        raise CliError(f"sweep: unexpected argument {args.dir!r} (the output goes to --out DIR)")
    if not args.sweep.strip():
        raise CliError("sweep: empty sweep file name; give the sweep's .yaml file")
    if args.out is None or not args.out.strip():
        raise CliError("sweep: --out DIR is required: the directory for the sweep's outputs")
    if args.workers is not None and not 1 <= args.workers <= MAX_WORKERS:
        raise CliError(f"--workers {args.workers}: must be in [1, {MAX_WORKERS}]")
    if args.ray is not None and not args.ray.strip():
        raise CliError("--ray: empty address; give a Ray cluster's address, or --ray alone")
    # The closed loop loads only here (``--help`` stays fast).
    from conesim.envs.sweep import run_sweep  # noqa: PLC0415
    from conesim.envs.sweep_file import load_sweep  # noqa: PLC0415
    from conesim.envs.sweep_store import SweepDirError, check_sweep_dir  # noqa: PLC0415
    from conesim.envs.sweep_workers import (  # noqa: PLC0415
        RayStartError,
        default_workers,
        ray_session,
    )

    sweep = load_sweep(args.sweep)
    out = Path(args.out)
    try:
        check_sweep_dir(out, sweep)
    except SweepDirError as exc:
        raise CliError(f"--out {exc}") from None
    if args.ray is not None:
        _check_ray_extra()
    with contextlib.ExitStack() as stack:
        if args.ray is not None:  # started or reached before anything is written
            address = None if args.ray == "local" else args.ray
            try:
                stack.enter_context(ray_session(args.workers or default_workers(), address))
            except RayStartError as exc:
                raise CliError(f"--ray: {exc}") from None
        try:
            report = run_sweep(
                sweep, out, workers=args.workers, ray=args.ray, pictures=args.pictures,
                stderr=sys.stderr, tty=sys.stderr.isatty(),
            )  # fmt: skip
        except KeyboardInterrupt:
            print(
                f"conesim sweep: interrupted; the runs finished are in {out / 'results.jsonl'}, "
                "and the same command resumes the sweep",
                file=sys.stderr,
            )
            return EXIT_INTERRUPTED
        except OSError as exc:
            raise CliError(f"--out {out}: cannot write the results ({os_reason(exc)})") from None
    sys.stdout.write(report.summary)
    print(
        f"\n{report.total} runs: {report.skipped} done before, {report.ran} run now; "
        f"{report.clean} clean, {report.errors} errors. Wrote {out / 'results.jsonl'}, "
        f"{out / 'summary.md'}, {out / 'summary.png'}, {out / 'failed.md'}"
    )
    return EXIT_OK if report.clean == report.total else EXIT_FAILED


def cmd_sweep_summary(args: argparse.Namespace) -> int:
    """``conesim sweep summary DIR``: write and print the summary again."""
    from conesim.envs.sweep_summary import write_summary  # noqa: PLC0415

    if args.dir is None or not args.dir.strip():
        raise CliError("sweep summary: give the sweep's directory: conesim sweep summary DIR")
    if args.out is not None or args.workers is not None or args.ray is not None:
        raise CliError("sweep summary: takes only DIR (no --out, --workers or --ray)")
    try:
        text = write_summary(Path(args.dir))
    except FileNotFoundError as exc:
        raise CliError(str(exc)) from None
    except OSError as exc:
        raise CliError(f"{args.dir}: cannot write the summary ({exc.strerror or exc})") from None
    sys.stdout.write(text)
    return EXIT_OK


def _check_ray_extra() -> None:
    try:
        import ray  # noqa: F401, PLC0415
    except ImportError:
        raise CliError(
            '--ray needs Ray: install the ray extra, pip install "conesim[ray]"'
        ) from None

"""granchain command line: run, compare, plan, predict, plot, render, collect, scenes, materials, doctor, campaign.

Each subcommand is a pair of functions in the module of its kind (``add_<name>_parser`` and
``cmd_<name>``): runs.py (run, compare, compare-laws, accuracy), info.py (plan, predict, scenes,
materials, doctor), directories.py (render, collect, plot), campaign.py, submit.py; common.py holds
what they share.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from granchain._version import __version__
from granchain.exceptions import GranchainError
from granchain.scene import bundled_scenes as bundled_scenes

from .directories import add_collect_parser, add_plot_parser, add_render_parser
from .info import add_doctor_parser, add_materials_parser, add_plan_parser, add_predict_parser, add_scenes_parser
from .runs import add_accuracy_parser, add_compare_laws_parser, add_compare_parser, add_run_parser
from .terminal import DEFAULT_SCENE as DEFAULT_SCENE
from .terminal import JSON_SCHEMA_VERSION as JSON_SCHEMA_VERSION
from .terminal import auto_np as auto_np
from .terminal import check_out, shown, tolerant_output
from .terminal import json_safe as json_safe
from .terminal import np_arg as np_arg
from .terminal import planned as planned
from .terminal import print_json as print_json
from .terminal import print_result as print_result
from .terminal import resolve_scene as resolve_scene


def build_parser() -> argparse.ArgumentParser:
    """The parser of every subcommand, in the order ``granchain --help`` lists them."""
    from granchain.cli.campaign import add_campaign_parser
    from granchain.cli.submit import add_submit_parser

    p = argparse.ArgumentParser(prog="granchain", description="Stress waves in 1D granular chains.")
    p.add_argument("--version", action="version", version=f"granchain {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    add_run_parser(sub)
    add_predict_parser(sub)
    add_plan_parser(sub)
    add_compare_parser(sub)
    add_compare_laws_parser(sub)
    add_plot_parser(sub)
    add_accuracy_parser(sub)
    add_render_parser(sub)
    add_collect_parser(sub)
    add_doctor_parser(sub)
    rp = sub.add_parser(
        "reproduce",
        help="regenerate the paper's figures and printed numbers, with verdicts (granchain reproduce --help)",
        add_help=False,
    )
    rp.add_argument("rest", nargs=argparse.REMAINDER)  # main() hands these to granchain.reproduce.main
    add_scenes_parser(sub)
    add_materials_parser(sub)
    add_campaign_parser(sub)
    add_submit_parser(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    """The ``granchain`` command: parse argv, run the subcommand, return its exit status (a
    GranchainError is one line and exit 2; anything else keeps its traceback)."""
    from granchain import progress

    tolerant_output()
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["reproduce"]:  # its own parser (argparse's REMAINDER drops leading options)
        from granchain import reproduce

        return reproduce.main(argv[1:])
    args = build_parser().parse_args(argv)

    def one_line(message, category, filename, lineno, file=None, line=None):
        print(f"granchain: warning: {shown(message)}", file=sys.stderr)

    try:
        with warnings.catch_warnings(), progress.quiet(getattr(args, "quiet", False)):
            warnings.showwarning = one_line
            warnings.simplefilter("always", UserWarning)
            check_out(args)
            return args.func(args)
    except GranchainError as e:  # a user's error: one line; anything else is a bug and keeps its traceback
        print(f"granchain: error: {shown(e)}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # `granchain predict | head`: the reader has what it wanted
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - no flush error at exit
        return 0
    except KeyboardInterrupt:
        print("granchain: interrupted; no run directory was written", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())

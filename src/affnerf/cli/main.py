"""The ``affnerf`` command: one verb per job, each a thin layer over the Python API.

Errors caused by input print one line (``affnerf: error: <file>: <problem>``) and exit with code 2;
``--debug`` (anywhere on the command line) shows the traceback instead.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence

from tyro.extras import SubcommandApp

from affnerf.errors import AffnerfError


def build_app(args: Sequence[str] = ()) -> SubcommandApp:
    """The command tree (``args`` lets ``train`` take its defaults from the preset they name)."""
    from affnerf.cli import data, demo, evaluate, grasp
    from affnerf.cli.bench import bench
    from affnerf.cli.predict import predict
    from affnerf.cli.segmenter import train_segmenter
    from affnerf.cli.train import make_train_command
    from affnerf.cli.view import view

    app = SubcommandApp()
    app.command(data.app, name="data", help="Generate, import, index, preview and summarise datasets.")
    app.command(make_train_command(args), name="train")
    app.command(train_segmenter, name="train-segmenter")
    app.command(predict, name="predict")
    app.command(evaluate.app, name="eval", help="Evaluate like the paper's Table 2 (and, with `eval grasp`, Table 3).")
    app.command(evaluate.metrics, name="metrics")
    app.command(grasp.app, name="grasp", help="Plan parallel-jaw grasps on a labelled mesh, or score given grasps.")
    app.command(view, name="view")
    app.command(bench, name="bench")
    app.command(demo.demo, name="demo", help="Run the whole pipeline at a small scale on this machine.")
    return app


class _OneLineFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        return f"affnerf: {record.levelname.lower()}: {record.getMessage()}"


def _configure_logging(debug: bool) -> None:
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(_OneLineFormatter())
    root = logging.getLogger("affnerf")
    root.handlers[:] = [handler]
    root.setLevel(logging.DEBUG if debug else logging.INFO)
    root.propagate = False


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (0 success, 2 bad input, 130 interrupted)."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    args = [a for a in args if a != "--debug"]
    _configure_logging(debug)
    try:
        from affnerf.cli.train import strip_flag

        build_app(args).cli(prog="affnerf", args=strip_flag(args, "--config-file"))
    except AffnerfError as exc:
        if debug:
            raise
        print(f"affnerf: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into a program that stopped reading (e.g. head)
        return 0
    except OSError as exc:  # e.g. a read-only or full disk: name the file, keep it to one line
        if debug:
            raise
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"affnerf: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("affnerf: interrupted", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())

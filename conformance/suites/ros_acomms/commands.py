"""The ros_acomms suite's own command: ``ros-msg-files``, an edition's .msg and .srv files."""

from __future__ import annotations

from pathlib import Path

NAMES = ("ros-msg-files",)


def add(sub) -> None:
    files = sub.add_parser("ros-msg-files", help="write ros_acomms_msgs .msg and .srv files of an edition")
    files.add_argument("folder", type=Path, help="where to write msg/ and srv/ (created if need be)")
    files.add_argument("--edition", help="the edition (default: the suite's first: seed; or 9.0.0)")
    files.add_argument("--replace", action="store_true", help="replace files that are there already")
    files.set_defaults(func=command)


def command(args) -> int:
    from ...arguments import chosen_edition
    from ...errors import UsageError
    from . import load
    from .package_files import write_package
    from ...core.wording import counted

    suite = load()
    edition = chosen_edition(suite, args.edition)
    try:
        written, left_out = write_package(suite.defs.edition(edition), args.folder, args.replace)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    print(f"wrote {counted(len(written), 'file')} under {args.folder}" +
          (f"; left out of edition {edition}: {', '.join(left_out)}" if left_out else ""))
    return 0

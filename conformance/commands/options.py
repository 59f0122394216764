"""The command line's shared options, in one place: building them imports nothing heavy. The types of their values
are ``arguments``."""

from __future__ import annotations

from pathlib import Path

from ..arguments import count, megabytes, port, shard, startup_seconds, system_id, time_scale, timeout_seconds
from ..suites import names as suite_names, variants as suite_variants

REPORTS = ("json", "junit", "markdown", "html")
DEFAULT_MEMORY_MB = 2048


# ---------------------------------------------------------------- option groups

def add_suite(parser, by_format: bool = False) -> None:
    """--suite; ``by_format``: its default is the suite whose format the input is (a log's)."""
    parser.add_argument("--suite", default=None if by_format else suite_names()[0], choices=suite_names(),
                        help=("default: the suite reading the first log's format (LSF: imc, a ROS 1 bag: ros_acomms); "
                              "imc: " if by_format else "imc (default): ")
                        + "IMC messages 150-216; ros_acomms: ros_acomms_msgs types; "
                        + "; ".join(f"{name}: {text}" for name, (_, text) in suite_variants().items()))


def add_selection(parser) -> None:
    add_suite(parser)
    parser.add_argument("--edition", help="the edition to judge against (default: the suite's first); imc: imc-5.4.30 "
                                          "(what imcpy and deployed DUNE speak) or imc-5.4.11 (the seeds as written)")
    parser.add_argument("--message", action="append", default=[], metavar="NAME",
                        help="only this message or type (repeatable)")
    parser.add_argument("--id", action="append", default=[], metavar="GLOB", help="only case ids matching (repeatable)")
    parser.add_argument("--tag", action="append", default=[], help="only cases with this tag (repeatable), e.g. invalid")
    parser.add_argument("--shard", type=shard, metavar="K/N",
                        help="only the Kth of N shards of the selection (by each case id's hash: stable when cases "
                             "are added); report --merge joins the N results")
    parser.add_argument("--vectors", type=Path, metavar="DIR",
                        help="a suite folder (like vectors/imc) or folder of case files to use instead of the packaged corpus")


def add_reports(parser) -> None:
    for fmt in REPORTS:
        parser.add_argument(f"--{fmt}", metavar="FILE", help=f"write the {fmt} report to FILE")


def add_adapter(parser, *, what: str = "an implementation") -> None:
    """How to reach an implementation: a built-in or library adapter, a subprocess, or a socket."""
    parser.add_argument("--adapter", help=f"{what}: a built-in adapter of the suite (imc: imcpy, the default, pyimclsts, "
                                          "imcpy-shim, pyimclsts-shim, dune-cpp; ros_acomms: rosbags, the default, "
                                          "genpy, roscpp), or a library adapter as module:attribute or "
                                          "file.py:attribute (an object, a class or a factory)")
    parser.add_argument("--adapter-arg", action="append", default=[], metavar="NAME=VALUE",
                        help="an argument for a library adapter's class or factory, or a built-in adapter's, e.g. "
                             "edition=9.0.0, or the last arguments of an --adapter-cmd program, e.g. path=transport "
                             "(repeatable)")
    parser.add_argument("--adapter-cmd", metavar="CMD", help="a subprocess adapter speaking JSON lines "
                                                             "(adapters/README.md); split like a shell would, but never "
                                                             "run by one")
    parser.add_argument("--adapter-socket", metavar="URL",
                        help="an implementation serving the same JSON lines on a socket: tcp://HOST:PORT "
                             "(IPv6 as tcp://[::1]:PORT) or unix:PATH")
    parser.add_argument("--timeout", type=timeout_seconds, default=5.0,
                        help="seconds per request for subprocess and socket adapters (default 5)")
    parser.add_argument("--memory-limit", type=megabytes, default=DEFAULT_MEMORY_MB, metavar="MB",
                        help=f"data memory a subprocess adapter may use (default {DEFAULT_MEMORY_MB}; 0: no limit): one "
                             "that tries to allocate what a hostile length asks for fails instead of the machine")


def add_target(live, what: str) -> None:
    """A live target and how to treat it (``run`` and ``fuzz``): where it is, who the session is, what it may be
    asked, how to restart it."""
    live.add_argument("--target", metavar="URL", help=f"a live node to {what}: udp://HOST:PORT or "
                                                      "imc+udp://HOST:PORT/ (IPv6 as udp://[::1]:PORT)")
    live.add_argument("--bind", metavar="HOST[:PORT]", help="where the session listens (default: loopback, any port)")
    live.add_argument("--src", type=system_id, default=None, metavar="ID",
                      help="the session's own IMC id (default: one of 0x4C01-0x4CFE, chosen for the run); its second "
                           "client takes the next id")
    live.add_argument("--dst", type=system_id, default=None, metavar="ID",
                      help="the node's IMC id: start at once instead of waiting for a frame from the node")
    live.add_argument("--startup", type=startup_seconds, default=10.0, metavar="SECONDS",
                      help="how long to wait for a first valid frame from the target (default 10)")
    live.add_argument("--allow-multicast", action="store_true",
                      help="allow a multicast or broadcast target or bind (never needed on loopback)")
    live.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                      help="what a scenario needs from the target, e.g. peer=lauv-xplore-2 (list --scenarios names them)")
    live.add_argument("--allow-effects", nargs="?", const="all", metavar="EFFECTS",
                      help="send requests with side effects on the target: all, or a comma-separated list "
                           "(default: only effect-free ones)")
    live.add_argument("--profile", metavar="NAME", help="where deployed practice differs from the seeds (default seed)")
    live.add_argument("--time-scale", type=time_scale, default=1.0, metavar="F",
                      help="multiply every time bound by F (slow links)")
    live.add_argument("--replay-effects", action="store_true",
                      help="also send accepted frames of messages with effects (their destinations are the "
                           "generator's own: never against a real vehicle)")
    live.add_argument("--restart-cmd", metavar="CMD",
                      help="a command that restarts the target (split like a shell would, never run by one): "
                           "lets the robustness phase bisect to the frame that silenced it")


def add_judging(parser, log: bool = False) -> None:
    """The options pcap, watch and log share: what to judge against, which frames, how to report (``log``: a log's,
    whose format chooses the suite and which has no UDP ports)."""
    add_suite(parser, by_format=log)
    parser.add_argument("--vectors", type=Path, metavar="DIR",
                        help="a suite folder whose definitions to judge with (e.g. one made by generate --from)")
    parser.add_argument("--edition", help="the edition to judge against (default: the suite's first)")
    if not log:
        parser.add_argument("--port", action="append", type=port, default=[], metavar="PORT",
                            help="UDP ports carrying the suite's frames (repeatable; default imc: 6001-6030, "
                                 "30100-30104)")
    parser.add_argument("--message", action="append", default=[], metavar="NAME", help="only this message (repeatable)")
    parser.add_argument("--list-frames", type=count, default=20, metavar="N",
                        help="failing frames listed per message and rule (default 20)")
    parser.add_argument("--time-scale", type=time_scale, default=1.0, metavar="F",
                        help="multiply every exchange's time bound by F (slow links)")
    parser.add_argument("--strict", action="store_true", help="NON_STRICT (a SHOULD not met) and INCONCLUSIVE fail too")

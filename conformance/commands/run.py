"""``imc-conformance run``: a suite's corpus against an implementation (an adapter) or a live node (``--target``)."""

from __future__ import annotations

import datetime as dt
import gc
import json
import sys
from contextlib import contextmanager
from pathlib import Path

from ..errors import UsageError
from ..escaping import printable
from .options import add_adapter, add_reports, add_selection, add_target
from ..core.wording import counted


def add(sub) -> None:
    run = sub.add_parser("run", help="run a suite's corpus against an implementation")
    add_adapter(run)
    add_selection(run)
    run.add_argument("--errata", metavar="KEY", help="the implementation errata that explain failures "
                                                     "(default: the key the adapter's hello declares)")
    run.add_argument("--strict", action="store_true", help="NON_STRICT verdicts fail too")
    run.add_argument("--require", metavar="MESSAGE", action="append", default=[],
                     help="a coverage gate: the run fails (exit 1) when this message (repeatable; 'all': every message "
                          "of the run) was not tested. Without it, a message the implementation does not do is "
                          "reported as not tested and does not fail the run")
    run.add_argument("--waivers", metavar="FILE", help="JSON waivers: case ids, globs, rules or cause keys, each with a "
                                                       "reason and optional expiry")
    run.add_argument("--write-waivers", metavar="FILE", help="write today's failures as a starting waivers file")
    run.add_argument("--by", choices=("case", "cause"), default="case",
                     help="what each waiver --write-waivers writes names: a failing case (default), or a cause of the "
                          "report's 'Failures by cause' (one waiver per cause)")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument("--last-failed", "--lf", metavar="FILE",
                     help="run again only the cases that did not pass in FILE, a result saved by run --json (a failing "
                          "verdict, NON_STRICT or INCONCLUSIVE), narrowed further by --message, --id and --tag; the "
                          "edition is the result's unless --edition is given; nothing to run again exits 0")
    run.add_argument("--exitfirst", "-x", action="store_true",
                     help="stop at the first case that fails (under --strict, NON_STRICT and INCONCLUSIVE too): the "
                          "reports hold the cases done by then")
    live = run.add_argument_group("scenarios and live targets")
    add_target(live, "run the scenarios against")
    live.add_argument("--claims", metavar="FILE",
                      help='JSON {"services": [...], "capabilities": {NAME: "any"|"self"|"none"}}: what the target '
                           "serves, and to whom (list --scenarios lists the capabilities); the cases of a capability it "
                           "does not serve to the suite are UNSUPPORTED, not claimed")
    live.add_argument("--pcap", metavar="FILE", help="write every datagram of the run as pcapng, each commented "
                                                     "with its scenario and step (imc-conformance pcap replays it)")
    live.add_argument("--dry-run", action="store_true", help="print what the scenarios would send, and send nothing")
    live.add_argument("--robustness", action="store_true",
                      help="also run the robustness phase: every corpus frame, then 10,000 garbage datagrams, "
                           "after which every request kind answered before must still be answered")
    add_reports(run)
    run.set_defaults(func=command)


def selection(args, rerun: frozenset[str] | None = None):
    """The suite, the cases of its corpus that were read, the cases the options select (in the shard ``--shard``
    names; only those of ``rerun`` when given) and those the selection holds in all shards. Only the files of
    the selected messages are read (``--message``, an id glob naming one, or the cases to rerun) unless the run
    needs the whole corpus (waivers name any case; the robustness phase replays every frame)."""
    from ..arguments import known_groups
    from ..core.cases import select_cases
    from ..files import open_corpus

    whole = getattr(args, "waivers", None) or getattr(args, "robustness", False)
    suite, everything = open_corpus(args.suite, args.vectors, None if whole else selected_groups(args, rerun))
    args.edition = args.edition or suite.editions[0]
    if args.edition not in suite.editions:
        raise UsageError(f"unknown edition {args.edition!r} of the suite {suite.name!r} "
                         f"(editions: {', '.join(suite.editions)})")
    known_groups(suite, args.message, [g.name for g in suite.groups])
    known_groups(suite, [name for name in getattr(args, "require", ()) if name != "all"], [g.name for g in suite.groups])
    chosen = select_cases(everything, args.edition, args.message, args.id, args.tag, ids=rerun)
    return suite, everything, select_cases(chosen, args.edition, shard=args.shard), chosen


def selected_groups(args, rerun: frozenset[str] | None = None) -> frozenset[str] | None:
    """The groups (messages, types) the selection can only come from, or None when it may come from any."""
    if args.message:
        return frozenset(args.message)  # an id glob only narrows them further
    if rerun is not None:
        return frozenset(case_id.split("/")[1] for case_id in rerun if "/" in case_id)
    named = set()
    for glob in args.id:
        parts = glob.split("/")
        if len(parts) < 2 or any(c in parts[1] for c in "*?["):
            return None
        named.add(parts[1])
    return frozenset(named) or None


def command(args) -> int:
    from .. import live
    from ..core.runner import run_cases
    from ..core.session import AdapterStartError
    from ..core.waivers import WaiverError
    from ..files import load_waivers
    from ..render.terminal import print_result
    from .adapters import adapter_choice, open_session
    from .output import report_targets, say_untested, terminal, write_reports
    from .provenance import provenance

    targets = report_targets(args)
    rerun, rerun_notes = last_failed(args)
    if rerun is not None and not rerun:
        print(f"imc-conformance: every case of {printable(args.last_failed)} passed: nothing to run again")
        return 0
    suite, everything, cases, chosen_cases = selection(args, rerun)
    total = len(chosen_cases)
    gc.freeze()  # the corpus stays loaded to the end: the collector need never walk it again
    try:
        options = live.options(args, suite, everything)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    cases, held_notes = hold_practices(cases, options)
    if args.target and (args.adapter or args.adapter_cmd or args.adapter_socket):
        raise UsageError("give either --target (a live node) or --adapter/--adapter-cmd/--adapter-socket, not both")
    name, argv = (args.target, None) if args.target else adapter_choice(args, suite)
    if not total:
        raise UsageError("the selection matches no case")  # a shard of none is a result of none (merged later)
    if getattr(args, "by", "case") != "case" and not args.write_waivers:
        raise UsageError("--by says what the waivers --write-waivers writes name: give --write-waivers FILE too")
    if args.dry_run:
        if args.pcap:
            raise UsageError("--pcap records what a run sends and receives; --dry-run sends nothing")
        return live.dry_run(suite, cases, args, options)
    waivers, notes, waived = {}, [], None
    if args.waivers:
        try:
            waivers, notes, waived = load_waivers(Path(args.waivers), everything,
                                                  set(suite.kinds["vector"].codec.rules), dt.date.today())
        except WaiverError as exc:
            raise UsageError(str(exc)) from exc
    chosen = {"message": args.message, "id": args.id, "tag": args.tag, "cases": total}
    made = provenance(args, suite, chosen | ({"last_failed": args.last_failed} if args.last_failed else {}),
                      waivers=waived)
    console = terminal()
    args.first_unique = live.first_unique() if args.target else None
    recorder = open_recording(args, suite, cases, options)
    try:
        session = live.open_target(args, suite, recorder) if args.target else open_session(name, argv, args, suite)
    except ValueError as exc:
        if recorder is not None:
            recorder.close(complete=False)
        raise UsageError(str(exc)) from exc
    result = None
    try:
        with progress_bar(args.no_progress) as progress:
            result = run_cases(session, suite, cases, edition=args.edition, adapter=name, errata=args.errata,
                               waivers=waivers, strict=args.strict,
                               notes=rerun_notes(len(cases)) + notes + held_notes + live.notes(args, options),
                               progress=progress, options=options, provenance=made, exitfirst=args.exitfirst,
                               shard=args.shard, selection=chosen_cases if args.shard else None,
                               corpus=everything)
    except AdapterStartError as exc:
        raise UsageError(str(exc)) from exc
    finally:
        session.close()
        if recorder is not None:
            # a run stopped at its first failure (--exitfirst) recorded only part of the exchange, as an interrupted one
            recorder.close(complete=result is not None and result.complete)
    result.required = list(dict.fromkeys(args.require))
    if args.shard:
        result.notes.insert(0, f"shard {args.shard[0]} of {args.shard[1]}: {len(cases)} of the selection's {total} "
                               "cases")
    print_result(result, console)
    problems = write_reports(result, targets, console)
    if recorder is not None and recorder.failed:
        print(f"imc-conformance: cannot write the pcapng to {printable(str(args.pcap))}: {recorder.failed} (the run "
              "and its other reports went on)", file=sys.stderr)
        problems += 1
    elif recorder is not None:
        console.print(f"pcapng of the exchange ({recorder.count} datagrams): {printable(str(args.pcap))}",
                      highlight=False, markup=False)
    if args.write_waivers:
        problems += write_waivers(args, result, {c.id: c.data for c in cases}, console)
    if not result.complete and not result.stopped:
        print("imc-conformance: interrupted; the reports hold the cases done so far", file=sys.stderr)
        return result.exit_code()
    say_untested(result)
    return 2 if problems else result.exit_code()


def write_waivers(args, result, data: dict[str, dict], console) -> int:
    """``--write-waivers FILE``: the run's failures as a waivers file (``--by`` case or cause) the next run accepts,
    with a line on what it leaves out; none for a run that judged nothing. 1 if it cannot be written, else 0."""
    from ..core.waivers import cause_waivers_document, waivers_document
    from .output import write_file

    reason = f"failing on {dt.date.today().isoformat()} with {result.implementation}"
    if getattr(args, "by", "case") == "cause":
        doc, notes = cause_waivers_document(result, reason, data)
    else:
        doc, notes = waivers_document(result, reason)
    for note in notes:
        print(f"imc-conformance: --write-waivers: {printable(note)}", file=sys.stderr)
    if result.nothing_tested() is not None:
        return 0
    return write_file(Path(args.write_waivers), json.dumps(doc, indent=1) + "\n",
                      f"waivers file ({counted(len(doc['waivers']), 'waiver')})", console)


def last_failed(args):
    """What ``--last-failed FILE`` runs again: the ids of the cases that did not pass in the saved result (None
    without the option), and the note the report makes of the rerun given how many cases it runs. The result's
    edition is the run's unless ``--edition`` is given, and so is its built-in adapter unless another adapter or a
    target is; a result of another suite is a usage error."""
    if args.last_failed is None:
        return None, lambda selected: []
    from ..files import open_corpus, read_result

    shown = printable(args.last_failed)
    try:
        saved = read_result(Path(args.last_failed))
    except ValueError as exc:  # not JSON, unreadable, or not a valid result
        raise UsageError(f"--last-failed: cannot read the result {exc}") from exc
    if saved.suite != args.suite:
        raise UsageError(f"--last-failed {shown}: a result of the suite {saved.suite!r}, not of {args.suite!r} "
                         f"(give --suite {saved.suite})")
    args.edition = args.edition or saved.edition
    ids = saved.not_passed()
    if ids and not (args.adapter or args.adapter_cmd or args.adapter_socket or args.target):
        if saved.adapter not in open_corpus(args.suite)[0].adapters:
            raise UsageError(f"--last-failed {shown}: its cases were judged through {printable(saved.adapter)}; give "
                             "the same --adapter-cmd, --adapter-socket or --target to run them again")
        args.adapter = saved.adapter  # the implementation that failed them, not the suite's default

    def note(selected: int) -> list[str]:
        return [f"run again: {selected} of the {len(ids)} cases that did not pass in {shown}"
                + ("" if selected == len(ids) else " (the others are not selected, or not in this corpus and edition)")]
    return frozenset(ids), note


def hold_practices(cases: list, options: dict) -> tuple[list, list[str]]:
    """The byte vectors as the run's profile judges them: those about a rule of practice it holds (``practices``,
    e.g. DUNE's frame cap) are invalid for that rule; and a note saying how many."""
    from ..core.cases import Case
    from ..kinds.vector.provenance import held

    profile = options.get("profile") or {}
    practices = frozenset(profile.get("practices", ()))
    if not practices:
        return cases, []
    out = [Case(c.id, c.group, c.kind, held(c.data, practices)) if c.kind == "vector" else c for c in cases]
    changed = sum(1 for a, b in zip(cases, out) if a.data is not b.data)
    return out, [f"profile {profile['name']} holds the practice {', '.join(sorted(practices))}: {changed} cases about it "
                 "judged invalid instead of acceptable"]


@contextmanager
def progress_bar(off: bool):
    """A callback the runner reports its progress to: a transient bar on standard error, or nothing (rich's progress
    is imported only when shown)."""
    if off:
        yield None
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn

    with Progress("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=Console(stderr=True, emoji=False), transient=True) as bar:
        task = bar.add_task("running", total=None)
        yield lambda n: bar.update(task, completed=n)


def open_recording(args, suite, cases, options):
    """The recorder of ``--pcap`` (a live run's datagrams as pcapng), or None."""
    if not args.pcap:
        return None
    if not args.target:
        raise UsageError("--pcap records a live run's datagrams: give --target udp://HOST:PORT")
    from ..capture.recording import Recorder, about_run

    ids = [c.id for c in cases if c.kind == "scenario"]
    about = about_run(suite.name, args.edition, ids, options, args.target, args.src, args.dst, args.startup,
                      args.first_unique)
    try:
        Path(args.pcap).parent.mkdir(parents=True, exist_ok=True)
        return Recorder(Path(args.pcap), about)
    except OSError as exc:
        raise UsageError(f"cannot write the pcapng to {args.pcap}: {exc.strerror or exc}") from exc

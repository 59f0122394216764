"""``imc-conformance fuzz``: generated messages and mutated frames from the definitions, judged against one or more
implementations beside the reference codec; findings shrunk, classified, reported as ``run`` reports, and promoted
into the corpus on request."""

from __future__ import annotations

import argparse
import datetime as dt
import time
from pathlib import Path

from ..arguments import count, fuzz_count, megabytes, positive_seconds, timeout_seconds
from ..errors import UsageError
from .options import DEFAULT_MEMORY_MB, add_reports, add_suite, add_target
from ..core.wording import counted

DEFAULT_BUDGET = 100


def add(sub) -> None:
    fuzz = sub.add_parser("fuzz", help="hunt for deviations beyond the corpus with generated and mutated inputs")
    add_suite(fuzz)
    fuzz.add_argument("--edition", help="the edition to generate in (default: the suite's first)")
    fuzz.add_argument("--message", action="append", default=[], metavar="NAME",
                      help="only this message or type (repeatable; default: every one)")
    fuzz.add_argument("--adapter", action="append", default=[], metavar="NAME",
                      help="an implementation, as run --adapter takes it (repeatable: with several, each deviation is "
                           "classified by which implementations agree with the reference)")
    fuzz.add_argument("--adapter-cmd", action="append", default=[], metavar="CMD",
                      help="a subprocess adapter (repeatable), as run --adapter-cmd takes it")
    fuzz.add_argument("--adapter-arg", action="append", default=[], metavar="NAME=VALUE",
                      help="an argument for the library adapters' class or factory (repeatable)")
    fuzz.add_argument("--in-process", action="store_true",
                      help="run library adapters in this process (faster; by default each runs in a worker process, "
                           "so that its crash or hang is a finding with the input that caused it)")
    fuzz.add_argument("--timeout", type=timeout_seconds, default=5.0, help="seconds per request (default 5)")
    fuzz.add_argument("--memory-limit", type=megabytes, default=DEFAULT_MEMORY_MB, metavar="MB",
                      help=f"data memory of each adapter process (default {DEFAULT_MEMORY_MB}; 0: no limit)")
    fuzz.add_argument("--seed", type=count, default=0, metavar="N", help="the run's seed (default 0): the same seed "
                                                                         "and budget give the same findings")
    fuzz.add_argument("--budget", type=fuzz_count, default=DEFAULT_BUDGET, metavar="N",
                      help=f"examples generated per message and property (default {DEFAULT_BUDGET}); shrinking a "
                           "finding judges more")
    fuzz.add_argument("--duration", type=positive_seconds, metavar="S",
                      help="stop after S seconds, whatever is left of the budget (the run is then not reproducible)")
    fuzz.add_argument("--property", action="append", default=[], choices=("message", "frame"),
                      help="message: generated messages, encoded and decoded both ways; frame: mutated frames "
                           "(default: both)")
    fuzz.add_argument("--sweep", type=fuzz_count, default=0, metavar="N",
                      help="first, N mutations of each message's corpus frames drawn without hypothesis (the fast "
                           "engine: judged in batches, findings shrunk to the shortest frame)")
    fuzz.add_argument("--database", type=Path, help=argparse.SUPPRESS)  # refused with the reason (command)
    fuzz.add_argument("--promote", type=Path, metavar="FILE",
                      help="add the unexplained findings to this promoted-findings file (vectors/<suite>/promoted.json "
                           "in a checkout); imc-conformance generate makes them vectors")
    live = fuzz.add_argument_group("live fuzzing (--target): mutated requests sent to a node, then the robustness "
                                   "phase's probes find a request kind it stopped serving")
    add_target(live, "fuzz (with --allow-effects: it sends requests)")
    add_reports(fuzz)
    fuzz.set_defaults(func=command)


def command(args) -> int:
    from .. import __version__
    from ..core.cases import select_cases
    from ..core.runner import run_cases
    from ..core.session import AdapterStartError
    from ..files import open_corpus
    from ..fuzz import promote
    from ..fuzz.engine import Search
    from ..fuzz.report import fuzz_result, review, unexplained
    from ..render.terminal import print_result
    from ..core.hello import check_hello
    from .adapters import adapter_arguments, builtin_argv, open_session, split_command
    from ..arguments import chosen_edition, known_groups
    from .output import report_targets, say_untested, terminal, write_reports
    from .provenance import provenance

    targets = report_targets(args)
    if args.database is not None:
        raise UsageError("--database: a fuzzing run is seeded (the same seed and budget give the same findings), and "
                         "hypothesis keeps no example database for a seeded search; keep a finding with --promote FILE")
    if args.budget == 0:
        raise UsageError("--budget 0 judges nothing: give a positive number of examples")
    adapter_arguments(args)
    suite, everything = open_corpus(args.suite, None, None if args.target else frozenset(args.message) or None)
    edition = chosen_edition(suite, args.edition)
    known_groups(suite, args.message, [g.name for g in suite.groups])
    try:
        source = suite.fuzz_source(edition, everything)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    groups = [g for g in source.groups if not args.message or g in args.message]
    if args.target:
        return live_fuzz(args, suite, everything, source, groups, edition, targets)
    chosen = [(name, builtin_argv(name, suite, adapter_arguments(args))) for name in args.adapter] + [
        (cmd, split_command(cmd)) for cmd in args.adapter_cmd]
    if not chosen:
        chosen = [(next(iter(suite.adapters)), None)]
    names = [name for name, _ in chosen]
    if len(set(names)) != len(names):
        raise UsageError("an implementation is named twice")
    sessions = {}
    try:
        for name, argv in chosen:
            try:
                sessions[name] = open_session(name, argv, args, suite, isolate=not args.in_process)
            except ValueError as exc:
                raise UsageError(str(exc)) from exc
        hellos = [check_hello(s.hello(), suite.name, suite.encoding_param + "s", suite.encodings)
                  for s in sessions.values()]
        started = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
        began = time.monotonic()
        notes = [f"seed {args.seed}, budget {args.budget} examples per {suite.group_label} and property, edition "
                 f"{edition}; " + ("bounded by --duration: a rerun may judge more or fewer" if args.duration else
                                   "rerun with the same seed and budget for the same findings")]
        if len(sessions) > 1:
            corpus = select_cases([c for c in everything if c.kind == "vector"], edition, groups)
            flagged = review({name: run_cases(s, suite, corpus, edition=edition, adapter=name)
                              for name, s in sessions.items()})
            notes.append(f"corpus review: {len(flagged)} of {len(corpus)} vectors fail in every implementation with no "
                         f"erratum to explain it{': ' + ', '.join(flagged[:20]) if flagged else ''}"
                         f"{' ...' if len(flagged) > 20 else ''}")
        until = began + args.duration if args.duration else None
        search = Search(suite, source, sessions, edition, seed=args.seed, budget=args.budget, until=until)
        try:
            if args.sweep:
                search.sweep(groups, args.sweep)
            tally = search.run(groups, tuple(args.property) or ("message", "frame"))
        except KeyboardInterrupt:
            tally = search.tally
            tally.stopped = "interrupted"
    except AdapterStartError as exc:
        raise UsageError(str(exc)) from exc
    finally:
        for session in sessions.values():
            session.close()
    judged = sum(tally.judged.values())
    notes.append(f"{counted(judged, 'example')} judged, {counted(len(tally.findings), 'finding')} "
                 f"({unexplained(tally)} unexplained)"
                 + (f"; stopped early: {tally.stopped}" if tally.stopped else ""))
    result = fuzz_result(suite, source, tally, names, [h["implementation"] for h in hellos], edition, started=started,
                         duration=time.monotonic() - began, notes=notes)
    result.provenance = provenance(args, suite, selected(args), errata=", ".join(sorted(
        {h["errata"] for h in hellos if h["errata"]})) or None)
    console = terminal()
    print_result(result, console)
    problems = write_reports(result, targets, console)
    if args.promote is not None:
        records = [promote.entry(f, args.seed, names, edition, __version__, dt.date.today())
                   for f in tally.findings if f.unexplained]
        try:
            added = promote.merge(args.promote, suite.name, records)
        except (OSError, ValueError) as exc:
            raise UsageError(f"cannot promote into {args.promote}: {exc}") from exc
        console.print(f"promoted {counted(added, 'new finding')} into {args.promote} ({len(records) - added} were there "
                      "already); imc-conformance generate makes them vectors", highlight=False, markup=False)
    if tally.stopped == "interrupted":
        return 130
    say_untested(result)
    return 2 if problems or result.nothing_tested() else (1 if unexplained(tally) else 0)



def live_fuzz(args, suite, everything, source, groups, edition, targets) -> int:
    """``fuzz --target``: ``--budget`` mutations of each message's corpus frames (seeded, no hypothesis) take the
    corpus's place in the robustness phase, which sends them in paced blocks with the garbage after, probes every
    request kind the node served before, and (with ``--restart-cmd``) bisects to the frame that silenced it."""
    import random

    from .. import live
    from ..core.cases import Case
    from ..core.runner import run_cases
    from ..fuzz.engine import mutated_cases
    from ..render.terminal import print_result
    from .output import say_untested, terminal, write_reports
    from .provenance import provenance

    if args.adapter or args.adapter_cmd:
        raise UsageError("give either --target (a live node) or --adapter/--adapter-cmd, not both")
    if not args.allow_effects:
        raise UsageError("fuzz --target sends generated requests to a live node: give --allow-effects (all, or the "
                         "effects it may have), and never point it at a vehicle in service")
    if "robustness" not in suite.kinds:
        raise UsageError(f"the suite {suite.name!r} has no robustness probes to tell a node that stopped answering: "
                         "it cannot be fuzzed live")
    args.robustness, args.claims, args.dry_run = True, None, False
    args.first_unique = live.first_unique()
    try:
        options = live.options(args, suite, everything)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    rng = random.Random(f"{args.seed}/{suite.name}/live")
    generated = [Case(i, i.split("/")[1], "vector", case) for g in groups
                 for i, (case, _) in mutated_cases(source, g, rng, args.budget).items()]
    options["corpus"] = tuple(generated)
    probes = [c for c in everything if c.kind == "robustness"]
    notes = [f"live fuzzing: {len(generated)} mutated frames of {len(groups)} messages (seed {args.seed}, budget "
             f"{args.budget} per message), then the garbage; every request kind served before is probed after each "
             "block"] + live.notes(args, options)
    try:
        session = live.open_target(args, suite)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    try:
        result = run_cases(session, suite, probes, edition=edition, adapter=args.target, options=options, notes=notes,
                           provenance=provenance(args, suite, selected(args)))
    finally:
        session.close()
    console = terminal()
    print_result(result, console)
    problems = write_reports(result, targets, console)
    say_untested(result)
    return 2 if problems else result.exit_code()


def selected(args) -> dict:
    """What a fuzzing run's result records of what it generated from (``Provenance.selection``)."""
    return {key: getattr(args, key) for key in ("message", "property", "seed", "budget", "sweep", "duration")}

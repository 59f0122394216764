"""``imc-conformance pcap``: judge captured traffic (pcap, pcapng) frame by frame and exchange by exchange."""

from __future__ import annotations

import datetime as dt
import mmap
import sys
import time
from pathlib import Path

from ..errors import UsageError
from ..limits import PIPE_LIMIT
from ..arguments import address, chosen_edition, count, known_groups, offset_seconds, window
from .options import add_adapter, add_judging, add_reports


def add(sub) -> None:
    pcap = sub.add_parser("pcap", help="judge captured traffic (pcap or pcapng): every frame, every exchange")
    pcap.add_argument("files", nargs="+", metavar="FILE", help="pcap or pcapng captures (Ethernet, raw IP, Linux "
                                                                "cooked SLL/SLL2, BSD loopback; IPv4 and IPv6)")
    add_judging(pcap)
    pcap.add_argument("--src", type=address, metavar="ADDR|ID", help="only datagrams from this IP address or system id")
    pcap.add_argument("--dst", type=address, metavar="ADDR|ID", help="only datagrams to this IP address or system id")
    pcap.add_argument("--host", type=address, metavar="ADDR|ID",
                      help="only datagrams from or to this IP address or system id (keeps whole exchanges)")
    pcap.add_argument("--start", type=offset_seconds, metavar="SECONDS", help="only from this many seconds into the capture")
    pcap.add_argument("--end", type=offset_seconds, metavar="SECONDS", help="only until this many seconds into the capture")
    replay_group = pcap.add_argument_group("the capture as a corpus: its frames through an implementation's decode")
    add_adapter(replay_group, what="decode every distinct captured frame with this implementation (where it disagrees "
                                   "with the reference is reported)")
    replay_group.add_argument("--adapter-frames", type=count, default=100_000, metavar="N",
                              help="distinct frames decoded at most (default 100,000)")
    add_reports(pcap)
    pcap.set_defaults(func=command)


def capture_rules(args):
    """The suite, its capture rules and the edition the options name; usage errors for what they cannot be."""
    from ..files import open_suite

    suite = open_suite(args.suite, args.vectors)
    try:
        rules = suite.capture_rules()
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    edition = chosen_edition(suite, args.edition)
    known_groups(suite, args.message, rules.keys)
    return suite, rules, edition


def command(args) -> int:
    from ..capture.judge import CaptureJudge, Selection
    from .output import report_targets

    targets = report_targets(args)
    suite, rules, edition = capture_rules(args)
    window(args.start, args.end)
    selection = Selection(frozenset(args.port) or None, frozenset(args.message), args.src, args.dst, args.host,
                          args.start, args.end, args.list_frames, args.time_scale)
    judge = CaptureJudge(suite.name, rules, edition, selection)
    adapter = None  # (name, session)
    # started first: a mistaken adapter says so at once
    if args.adapter is not None or args.adapter_cmd is not None or args.adapter_socket is not None:
        from .adapters import started_session
        adapter = started_session(args, suite)
        judge.corpus_limit = args.adapter_frames
    try:
        return judged(args, suite, rules, selection, judge, adapter, targets)
    finally:
        if adapter is not None:
            adapter[1].close()


def judged(args, suite, rules, selection, judge, adapter, targets) -> int:
    """Judge the captures, replay a recorded run, decode the frames through an adapter; report; the exit code."""
    from .output import finish
    from .provenance import provenance

    started = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    began = time.perf_counter()
    damage, complete = [], True
    try:
        for path in args.files:
            damage += judge_file(judge, Path(path), len(args.files) > 1)
    except KeyboardInterrupt:
        complete = False
    if judge.records and not judge.datagrams and any("not Ethernet" in why for why in judge.skipped):
        raise UsageError(f"{'; '.join(why for why in judge.skipped if 'not Ethernet' in why)}: nothing to judge")
    result = judge.result(implementation=", ".join(Path(p).name for p in args.files), started=started,
                          duration=round(time.perf_counter() - began, 3), strict=args.strict, title=suite.title,
                          notes=damage, complete=complete)
    result.provenance = provenance(args, suite, {key: getattr(args, key) for key in (
        "message", "port", "src", "dst", "host", "start", "end")})
    if judge.about is not None and complete:
        try:
            merge(result, replay(judge.about, judge.commented, args.strict, selection.groups,
                                 judge.recording_complete), list(rules.keys), args.strict)
        except ValueError as exc:
            damage.append(f"the recorded run cannot be replayed: {exc}")
            result.notes.append(damage[-1])
    if adapter is not None and complete:
        merge(result, decoded_by(judge, suite, adapter, args), list(rules.keys), args.strict)
    return finish(result, targets, damage, complete)


def judge_file(judge, path: Path, named: bool) -> list[str]:
    """Feed every record of the capture at ``path`` to the ``CaptureJudge``; what the reports should say of it (its
    damage: the records before it are judged; a recorded run's description that cannot be read)."""
    from ..capture.recording import run_ended
    from ..capture.records import CaptureError, records


    buf = read_capture(path)
    source, sections, said = f"{path.name} " if named else "", [], []
    try:
        for record in records(buf, sections):
            if sections and judge.about is None and not said:
                said += recorded_run(judge, path, sections, named)
            judge.feed(record, source)
    except CaptureError as exc:
        if not judge.records:
            raise UsageError(f"{path}: {exc}") from None
        return said + [f"{path}: {exc}; the records before it are judged"]
    finally:
        if isinstance(buf, mmap.mmap):
            buf.close()
    judge.recording_complete = run_ended(sections)
    return said


def recorded_run(judge, path: Path, sections: list[str], named: bool) -> list[str]:
    """Take the run a capture's section describes (``run --pcap``), to replay it; what to say if it cannot be."""
    from ..capture.recording import read_about

    try:
        about = read_about(sections)
    except ValueError as exc:
        return [f"{path}: {exc}; its frames and exchanges are judged, its scenarios not replayed"]
    if about is not None and named:
        raise UsageError(f"{path} is a recorded run (run --pcap): give it alone to replay its scenarios")
    judge.about, judge.keep_commented = about, about is not None
    return []


def read_capture(path: Path):
    """The bytes of a capture: a regular file mapped, a pipe or device read (at most PIPE_LIMIT bytes)."""

    try:
        if str(path) == "-":
            data = _read_stream(sys.stdin.buffer, path)
        else:
            with path.open("rb") as handle:
                if path.is_file() and path.stat().st_size > 0:
                    return mmap.mmap(handle.fileno(), 0, access=mmap.ACCESS_READ)
                data = _read_stream(handle, path)  # a pipe, a device, a file of /proc
    except OSError as exc:
        raise UsageError(f"cannot read {path}: {exc.strerror or exc}") from exc
    except ValueError as exc:  # mmap refused it
        raise UsageError(f"cannot read {path}: {exc}") from exc
    if not data:
        raise UsageError(f"{path}: empty, not a capture")
    if len(data) > PIPE_LIMIT:
        raise UsageError(f"{path}: more than {PIPE_LIMIT >> 20} MB through a pipe or device: write it to a file")
    return data


def _read_stream(handle, path: Path) -> bytes:
    """A capture from a stream: its first bytes must be a capture's (so /dev/zero is refused at once)."""
    from ..capture.records import PCAP_MAGICS, PCAPNG_SHB

    head = handle.read(4)
    if head and head not in PCAP_MAGICS and head != PCAPNG_SHB:
        raise UsageError(f"{path}: not a pcap or pcapng capture (it starts {head.hex()})")
    return head + handle.read(PIPE_LIMIT + 1 - len(head))


def replay(about: dict, datagrams: list, strict: bool, messages: frozenset, complete_: bool):
    """The scenario verdicts of a recorded run (those of ``messages``, when given), its engine replayed over the
    recorded datagrams on virtual time (robustness excluded: its restarts and floods cannot be replayed);
    ValueError if the recording cannot be."""
    from ..core.runner import run_cases
    from ..files import open_corpus
    from ..kinds.scenario import options as vocabulary
    from ..live import check_params
    from ..capture.recording import OWN, RECEIVED
    from ..sessions.replay import Recorded, ReplayLink

    try:
        suite, everything = open_corpus(about["suite"], None)
        profile = suite.profile(about["profile"])
    except (LookupError, ValueError) as exc:
        raise ValueError(f"the recorded run's suite or profile: {exc}") from None
    if about["edition"] not in suite.editions:
        raise ValueError(f"the recorded run's edition {about['edition']!r} is not one of the suite's")
    check_params(suite, everything, about["params"])  # what the live run would have refused, as it would have
    wanted = set(about["cases"])
    cases = [c for c in everything if c.id in wanted and c.kind == "scenario" and (not messages or c.group in messages)]
    options = {"params": dict(about["params"]), "effects": set(about["effects"]), "time_scale": about["time_scale"],
               "profile": profile, "robustness": False, "restart": False, "replay_effects": False,
               "corpus": tuple(c for c in everything if c.kind == "vector")}
    if about["claims"] is not None:  # a list of services in recordings made before claims named capabilities
        claims = about["claims"]
        try:
            options["claims"] = vocabulary.claims(suite.behaviour, {"services": claims} if isinstance(claims, list)
                                                  else {"capabilities": claims})
        except ValueError as exc:
            raise ValueError(f"the recorded run's claims: {exc}") from None
    if not datagrams:
        raise ValueError("no datagram of the run is in the capture")
    t0 = datagrams[0].time
    recording = [Recorded(d.time - t0, (d.src, d.sport), (d.dst, d.dport), d.payload, d.comment) for d in datagrams]
    sent = next((r for r in recording if r.comment not in (RECEIVED, OWN)), recording[0])
    link = ReplayLink(recording, target=sent.dst, address=sent.src, epoch0=t0, complete=complete_)
    session = suite.open_replay(link, target=about["target"], src=about["src"], dst=about["dst"],
                                startup=about["startup"], first_unique=about.get("first_unique"))
    result = run_cases(session, suite, cases, edition=about["edition"], adapter=about["target"], strict=strict,
                       options=options, clock=link.now, started=_iso(t0))
    if not result.complete:
        result.notes.insert(0, "the recording ends before its run did (interrupted, or the file cut): only the "
                               "scenarios that finished within it are replayed")
    return result


def decoded_by(judge, suite, adapter: tuple, args):
    """The capture as a corpus: each distinct frame decoded by the implementation, judged as a vector case whose
    verdict is the reference codec's."""
    from ..core.cases import Case
    from ..core.runner import run_cases
    from ..core.session import AdapterStartError

    cases = []
    for data, (group, number) in judge.corpus.items():
        case = judge.rules.vector_case(group, data, number, judge.edition)
        if case is not None:
            cases.append(Case(case["id"], group, "vector", case))
    notes = [f"{len(cases):,} distinct frames decoded by the adapter"
             + (f"; {judge.corpus_left:,} more not (--adapter-frames)" if judge.corpus_left else "")]
    try:
        result = run_cases(adapter[1], suite, cases, edition=judge.edition, adapter=adapter[0], strict=args.strict,
                           notes=notes)
    except AdapterStartError as exc:
        raise UsageError(str(exc)) from exc
    for m in result.messages:
        m.cases = collapsed(m.cases, {c.id: c.data for c in cases}, args.list_frames)
    return result


def collapsed(cases: list, data: dict, listed: int) -> list:
    """One case per message and expectation (``…/capture/decode/valid`` or ``…/decode/<rule>``) for a frame's
    decode cases: how many frames had each verdict, and the first failing ones."""
    from ..core.results import CaseResult, CheckResult
    from ..core.verdicts import Verdict, worst

    groups: dict[str, list] = {}
    for c in cases:
        groups.setdefault(c.id.rsplit("/", 1)[0] + "/" + (c.rule or "valid"), []).append(c)
    out = []
    for case_id, members in groups.items():
        counts: dict = {}
        for c in members:
            counts[c.verdict] = counts.get(c.verdict, 0) + 1
        checks = [CheckResult("count", v, f"{n:,} frame{'s' if n != 1 else ''}") for v, n in
                  sorted(counts.items(), key=lambda kv: kv[0].value)]
        bad = [c for c in members if c.verdict is not Verdict.PASS]
        for c in bad[:listed]:
            frame = c.id.rsplit("/", 1)[1]
            checks += [CheckResult(f"frame {frame}", k.verdict, k.detail, k.outcome, k.expected, k.actual, k.diffs,
                                   k.note, k.clause) for k in c.checks]
        if len(bad) > listed:
            checks.append(CheckResult("more", worst(counts), f"{len(bad) - listed:,} more not listed"))
        first = members[0]
        out.append(CaseResult(case_id, first.message, worst(counts), first.expect, first.clause, checks, first.rule,
                              sorted({e for c in members for e in c.errata})))
    return out


def merge(result, replayed, order: list[str], strict: bool) -> None:
    """Add a replay's scenario cases to a capture's result, each under its message."""
    from ..core.results import MessageResult, message_verdict

    groups = {m.name: m.cases for m in result.messages}
    for m in replayed.messages:
        groups.setdefault(m.name, []).extend(m.cases)
    rank = {name: i for i, name in enumerate(order)}
    keys = {m.name: m.key for m in result.messages + replayed.messages}
    result.messages = [MessageResult(name, keys[name], message_verdict(cases, strict), cases)
                       for name, cases in sorted(groups.items(), key=lambda kv: (rank.get(kv[0], len(rank)), kv[0]))]
    result.notes += [f"{len(replayed.cases):,} cases judged with {replayed.implementation} ({replayed.adapter})"]
    result.notes += replayed.notes
    result.incidents += replayed.incidents
    result.stderr += replayed.stderr


def _iso(t: float) -> str:
    return dt.datetime.fromtimestamp(t, dt.timezone.utc).isoformat(timespec="seconds")

"""adapter-check: a short, fixed set of requests through any adapter, and every mistake it makes in speaking the
contract explained with its fix. Suite-generic: the probes are the suite's own byte vectors (``probes``), judged by
its case kind as a run judges them (the one verdict policy); what adapter-check adds is why an answer is wrong.

A first pass decodes one valid frame of every group, to learn what the implementation reads; the probes then go to
those groups, so that a mistake in writing the values the adapter's own messages hold is seen.

An implementation's own failure on a probe (it accepts a frame with a wrong CRC, it decodes a value otherwise, it
hangs or dies on an input) is a finding, listed but not a mistake of the adapter; a failure the implementation's
errata explain is one too. A value answered the way a JSON writer typically gets it wrong (−0.0 as 0, an fp32 NaN
widened, a bare NaN) is a mistake, whose fix says so if the implementation itself is to blame. Where either could be
the cause (a frame holding another value than the request gave, a rule named that the input does not break) both
readings are shown, with how to tell them apart.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from ..core.hello import check_hello
from ..core.session import AdapterStartError, Answer, Job, Request
from ..core.verdicts import Verdict
from ..sessions.subprocess import SubprocessSession
from ..core.wording import counted
from . import wire
from .mistakes import Mistake, value_mistake
from .probes import FEATURES, Probe, choose, first_frames

FINE = (Verdict.PASS, Verdict.IMPL_DEFINED, Verdict.UNSUPPORTED)
GAVE_UP = "adapter keeps crashing"  # how a session says it gave up restarting a program that dies or hangs on each input
BARE_CONSTANT = re.compile(r"[:\[,]\s*-?(?:NaN|Infinity)\s*[,\]}]")  # a JSON writer's bare NaN or Infinity, as a value
IN_FLIGHT = 3  # requests sent together to see that each is answered with its own id
NO_HEADER = "encode-no-header"


@dataclass
class Outcome:
    """What adapter-check found: what was checked and right (``passed``), the ``mistakes`` (each explained), and the
    implementation's ``findings`` (a run shows them; not the adapter's fault)."""

    implementation: str | None = None
    passed: list[str] = field(default_factory=list)
    mistakes: list[Mistake] = field(default_factory=list)
    findings: list[str] = field(default_factory=list)
    # encode probes whose frame holds another value than the request gave: the implementation's result or the
    # adapter's mistake, which the frame alone cannot tell (each: where, what the frame holds); shown with both readings
    either: list[str] = field(default_factory=list)
    decoded_right: bool = False  # the same float probes were decoded right (the adapter writes those values right)
    reads: list[str] = field(default_factory=list)  # the groups a first pass found the implementation reads
    # rule mismatches the implementation's own check may explain (each: where, what was named): shown with both readings
    rules: list[str] = field(default_factory=list)
    nothing: bool = False  # every probe was answered "unsupported": the adapter implements nothing yet

    def add(self, found) -> None:
        for mistake in found:
            if all((m.code, m.seen) != (mistake.code, mistake.seen) for m in self.mistakes):
                self.mistakes.append(mistake)

    def by_kind(self) -> list[list[Mistake]]:
        """The mistakes, those of one kind (code) together, in the order they were first seen."""
        kinds: dict[str, list[Mistake]] = {}
        for mistake in self.mistakes:
            kinds.setdefault(mistake.code, []).append(mistake)
        return list(kinds.values())


def check(session, suite, cases: list, edition: str, timeout: float) -> Outcome:
    """Drive ``session`` (a library, subprocess or socket session, possibly wrapped) through the probes."""
    out = Outcome()
    kind = suite.kinds["vector"]
    probes = choose(cases, edition, kind.codec.rules)
    inner = getattr(session, "inner", session)
    if isinstance(inner, SubprocessSession):
        if not _line_by_line(inner, suite, kind, probes, edition, timeout, out):
            return out
    try:
        info = check_hello(session.hello(), suite.name, suite.encoding_param + "s", suite.encodings)
    except AdapterStartError as exc:
        if not out.mistakes:  # else what the line-by-line checks found is why
            out.add([Mistake("no-start" if isinstance(inner, SubprocessSession) else "hello-fields", str(exc), "hello")])
        return out
    out.implementation = info["implementation"]
    if not isinstance(inner, SubprocessSession):
        out.passed.append(f"hello: {info['implementation']!r}, suites {info['suites']}, emits {info['emits']}")
    if kind.name in info["kinds"]:
        reads = _reach(session, suite, kind, cases, edition, out)
        if reads is None:
            return out
        groups = {group for group, _ in reads}
        _probe(session, suite, kind, choose(cases, edition, kind.codec.rules, groups or None), edition, info, out,
               reads)
    else:
        out.passed.append(f"no probe sent: the adapter runs {' and '.join(info['kinds'])} cases, not {kind.name} ones")
    return out


def _reach(session, suite, kind, cases: list, edition: str, out: Outcome) -> set[tuple[str, str]] | None:
    """A first pass: one valid frame of each group decoded in each encoding, to learn what the implementation reads
    ((group, encoding) answered with a message); None when the adapter could not be reached."""
    jobs = []
    for case in first_frames(cases, edition):
        jobs += [Job(suite.name, case.id, r) for r in kind.plan(case.data, edition, frozenset())
                 if r.op == "decode"]
    groups = {case.id: case.group for case in cases}
    try:
        answered = list(session.run(jobs))
    except AdapterStartError as exc:
        out.add([Mistake("no-start", str(exc), "the first pass")])
        return None
    reads = {(groups[job.case_id], job.request.encoding) for job, answer in answered if answer.kind == "ok"}
    out.reads = sorted({group for group, _ in reads})
    if reads:
        shown = ", ".join(out.reads[:8]) + (f" and {len(out.reads) - 8} more" if len(out.reads) > 8 else "")
        total = len(set(groups.values()))
        out.passed.append(f"a first pass of {len(jobs)} decodes: it reads {len(out.reads)} of "
                          f"{counted(total, suite.group_label)} ({shown}); the probes go to those")
    return reads


def _line_by_line(inner, suite, kind, probes: list[Probe], edition: str, timeout: float, out: Outcome) -> bool:
    """The wire checks on a channel of their own; False when there is no hello to go on with."""
    try:
        channel = inner.open_channel()
    except AdapterStartError as exc:
        out.add([Mistake("no-start", str(exc), "start")])
        return False
    line = wire.Line(channel, timeout)
    try:
        info, found = wire.hello(line, suite.name, suite.encoding_param + "s", suite.encodings, lambda: inner.stderr,
                                 inner.hello_timeout)
        out.add(found)
        if info is None:
            return False
        out.passed.append(f"hello: {info['implementation']!r}, suites {info['suites']}, "
                          f"{suite.encoding_param}s {info[suite.encoding_param + 's']}, "
                          f"batch {'yes' if info.get('batch') is True else 'no'}")
        found = wire.unknown_op(line, suite.name)
        out.add(found)
        if not found:
            out.passed.append("an operation it does not know answered \"unsupported\"")
        vectors = kind.name in info.get("kinds", [kind.name])
        requests, expected = _decodes(kind, probes if vectors else [], edition, first=wire.UNKNOWN_OP_ID + 1)
        same = _matcher(kind, expected, edition)
        if requests and not line.ended:
            found, unanswered = wire.together(line, requests, same, batch=False)
            noted = len(out.findings)
            found, line, channel = _unanswered_alone(inner, suite, line, channel, requests, unanswered, found,
                                                     timeout, out)
            out.add(found)
            if not found and len(out.findings) == noted:
                out.passed.append(f"{len(requests)} requests in flight together, each answered with its own id")
        if requests and info.get("batch") is True and not line.ended:
            requests, expected = _decodes(kind, probes, edition, first=max(requests) + 1)
            found, unanswered = wire.together(line, requests, _matcher(kind, expected, edition), batch=True)
            noted = len(out.findings)
            found, line, channel = _unanswered_alone(inner, suite, line, channel, requests, unanswered, found,
                                                     timeout, out)
            out.add(found)
            inner.batch = not found  # the probes then go one a line, so that each is judged on its own
            if not found and len(out.findings) == noted:
                out.passed.append(f"a batch of {len(requests)} requests, each answered with its own id")
        found = wire.end_of_input(line)
        out.add(found)
        if not found and line.closed:
            out.passed.append("it exited at the end of its input")
    finally:
        channel.stop(kill=True)
    return True


def _unanswered_alone(inner, suite, line, channel, requests: dict[int, dict], unanswered: list[int],
                      found: list[Mistake], timeout: float, out: Outcome):
    """Requests sent together and not all answered: each unanswered one sent again alone, in order, to a fresh
    program. One unanswered alone too explains the rest (a program answering in order waits on it): the
    implementation hangs or dies on that input, its own result (a note); all answered alone, the adapter does not
    answer requests in flight (its mistake). Returns the mistakes left, and the line and channel to go on with."""
    missing = [m for m in found if m.code in ("pipelining", "batch-unread")]
    if not missing:
        return found, line, channel
    channel.stop(kill=True)
    for ident in unanswered:
        channel, line, greeted = _greeted(inner, suite, timeout)
        answered = {}
        if greeted:
            line.channel.send({"id": ident, **requests[ident]})
            answered, _ = line.collect({ident}, "alone", arrays=False)
        channel.stop(kill=True)
        if greeted and ident not in answered:
            status = "it died" if line.ended else f"no answer within {timeout:g} s"
            out.findings.append(f"request {ident} of those in flight ({requests[ident]['op']} of "
                                f"{requests[ident].get('frame', '')[:48]}…), sent again alone: {status}: the "
                                "implementation hangs or dies on this input, and the others waited behind it")
            found = [m for m in found if m not in missing]
            break
    channel, line, _ = _greeted(inner, suite, timeout)
    return found, line, channel


def _greeted(inner, suite, timeout: float):
    """A fresh program of the adapter, greeted: (channel, line, whether it answered hello)."""
    channel = inner.open_channel()
    line = wire.Line(channel, timeout)
    info, _ = wire.hello(line, suite.name, suite.encoding_param + "s", suite.encodings, lambda: inner.stderr,
                         inner.hello_timeout)
    return channel, line, info is not None


def _decodes(kind, probes: list[Probe], edition: str, first: int) -> tuple[dict[int, dict], dict[int, tuple]]:
    """Decode requests of the first valid probes (id -> request body), and what each should decode to."""
    requests, expected = {}, {}
    for probe in [p for p in probes if p.teaches in FEATURES][:IN_FLIGHT]:
        data = probe.case.data
        request = next(r for r in kind.plan(data, edition, set(kind.codec.encodings)) if r.op == "decode")
        ident = first + len(requests)
        requests[ident] = {"op": "decode", "suite": probe.case.id.split("/")[0], "frame": request.frame.hex(),
                           **request.params}
        expected[ident] = (data["message"], data.get("compare", {}).get("nan_payload", False))
    return requests, expected


def _matcher(kind, expected: dict[int, tuple], edition: str):
    """``same(ident, reply)``: the request whose expected message a decode reply holds (its own first), or None."""
    def same(ident: int, reply: dict):
        message = reply.get("message") if reply.get("ok") is True else None
        if not isinstance(message, dict):
            return None
        for candidate in sorted(expected, key=lambda i: i != ident):
            wanted, pinned = expected[candidate]
            try:
                if not kind.codec.differences(wanted, message, pinned, edition):
                    return candidate
            except (TypeError, ValueError, KeyError, AttributeError):  # an answer no comparison can read
                return None
        return None
    return same


def _probe(session, suite, kind, probes: list[Probe], edition: str, info: dict, out: Outcome,
           reads: set[tuple[str, str]] = frozenset()) -> None:
    """Every probe through the session, judged by the case kind; each answer that is not right explained. ``reads``:
    the (group, encoding) the first pass found the implementation reads: "unsupported" for frames of one of them,
    inputs of several kinds, calls a capability absent that it has.

    What either party could have caused is not the adapter's mistake: a probe left unanswered (the implementation hangs
    on it) where the adapter answers others is a note; a rule named that the input does not break is shown with both
    readings unless the adapter names that rule for inputs breaking different rules (then no check of the
    implementation's explains it)."""
    emits = frozenset(info["emits"])
    jobs, by_job = [], {}
    for probe in probes:
        for request in kind.plan(probe.case.data, edition, emits):
            jobs.append(Job(suite.name, probe.case.id, request))
            by_job[id(jobs[-1])] = probe
    carrier = next((p for p in probes if p.teaches in FEATURES and isinstance(p.case.data["message"].get("header"), dict)
                    and any(c.startswith("encode-") for c in p.case.data["checks"])), None)
    if carrier is not None and emits:
        encoding = next(e for e in kind.codec.encodings if e in emits)
        message = dict(carrier.case.data["message"], header={})
        jobs.append(Job(suite.name, carrier.case.id, Request(NO_HEADER, "encode", encoding, message=message,
                                                              params=kind.codec.params(carrier.case.data, "encode", encoding))))
        by_job[id(jobs[-1])] = carrier
    wrong_before = len(out.mistakes)
    try:
        answered = list(session.run(jobs))
    except AdapterStartError as exc:
        out.add([Mistake("no-start", str(exc), "the probes")])
        return
    out.nothing = bool(answered) and all(answer.kind == "unsupported" for _, answer in answered)
    answers = any(answer.kind in ("ok", "rejected") for _, answer in answered)
    float_decodes = []
    misnamed: dict[str, list[tuple[Probe, str, Mistake]]] = {}  # rule named -> the probes it was named for
    absent: list[tuple[Probe, Mistake]] = []  # "unsupported" for a frame of a group and encoding it reads
    for job, answer in answered:
        probe = by_job[id(job)]
        where = f"{job.request.check} of {probe.case.id}"
        if answer.kind == "unsupported" and job.request.op == "decode" and \
                (probe.case.group, job.request.encoding) in reads:
            absent.append((probe, Mistake("unsupported-read", f"answered \"unsupported\" ({answer.reason[:120]}) "
                                                              f"for a {probe.case.group} frame ({job.request.encoding}), "
                                                              "a message it decodes otherwise", where)))
            continue
        if answer.kind == "timeout" and answers:
            out.findings.append(f"{where}: TIMEOUT: {answer.reason}: the adapter answers other requests, so the "
                                "implementation hangs on this input")
            continue
        if job.request.check == NO_HEADER:
            out.add(_no_header(kind, probe, job.request, answer, edition, out))
            continue
        result = kind.judge(probe.case.data, edition, job.request, answer)
        if job.request.op == "decode" and probe.teaches in FEATURES:
            float_decodes.append(result.verdict is Verdict.PASS)
        if result.verdict in FINE:
            continue
        if job.request.op == "encode" and probe.teaches in FEATURES and answer.kind == "ok":
            out.either.append(f"{job.request.check} of {probe.case.id}: "
                              f"{_held(kind, probe, job.request, answer, edition) or result.detail}")
            continue
        explained = suite.implementation_errata(probe.case.id, info["errata"], probe.case.data.get("tags", ()))
        found = _explain(kind, probe, job.request, answer, result, edition)
        if isinstance(found, list) and found and found[0].code == "wrong-rule" and not explained:
            misnamed.setdefault(answer.rule, []).append((probe, where, found[0]))
        elif isinstance(found, list) and found and not explained:
            out.add(found)
        else:
            errata = f" (erratum {', '.join(explained)})" if explained else ""
            out.findings.append(f"{where}: {result.verdict.value}{errata}: {result.detail}")
    out.decoded_right = bool(float_decodes) and all(float_decodes)
    if len({probe.teaches for probe, _ in absent}) > 1:  # for inputs of several kinds: refusals called absence
        out.add([mistake for _, mistake in absent])
    else:  # one kind of input (e.g. an id it cannot tell from one it does not implement): the implementation may say so
        out.findings += [f"{m.where}: {m.seen} (a refusal says more)" for _, m in absent]
    for rule, named in misnamed.items():
        if len({probe.teaches for probe, _, _ in named}) > 1:  # one rule for inputs breaking different rules
            out.add([mistake for _, _, mistake in named])
        else:
            out.rules += [f"{where}: named {rule!r}; {mistake.seen}" for _, where, mistake in named]
    if len(out.mistakes) == wrong_before:
        floats = sum(p.teaches in FEATURES for p in probes)
        classes = sum(p.teaches.startswith("class:") for p in probes)
        out.passed.append(f"{len(jobs)} requests of {len(probes)} probes ({floats} with values the decoded form spells "
                          f"its own way, {classes} an implementation may accept or refuse, "
                          f"{len(probes) - floats - classes} breaking one rule each"
                          f"{', one encode without header fields' if carrier is not None and emits else ''}): "
                          "answered as the contract asks")


def _explain(kind, probe: Probe, request: Request, answer: Answer, result, edition: str) -> list[Mistake] | None:
    """The adapter's mistakes an answer that is not right shows; None when it is the implementation's own result."""
    where = f"{request.check} of {probe.case.id}"
    if answer.kind == "timeout":
        return [Mistake("late", answer.reason, where)]
    if answer.kind == "rejected":
        if result.verdict is Verdict.NON_STRICT:
            breaks = " and ".join(probe.breaks) or probe.teaches
            return [Mistake("wrong-rule", f"refused naming rule {answer.rule!r}; the input breaks {breaks} only (the "
                                          f"reference codec, rule by rule): {answer.reason}", where)]
        if result.verdict is Verdict.ADAPTER_ERROR:
            return [Mistake("unknown-rule", f"rule {answer.rule!r}: {answer.reason}", where)]
        return None
    if answer.kind == "adapter-error" and answer.reason.startswith(GAVE_UP):  # crashes or hangs on each replay
        return None
    if answer.kind == "adapter-error":
        if answer.reason.startswith("adapter failed: "):
            broken = (f" (an input breaking {' and '.join(probe.breaks)})" if probe.breaks else
                      f" ({FEATURES[probe.teaches]})" if probe.teaches == "null-message" else
                      f" (an input of {probe.teaches.replace(':', ' ')}, which an implementation may accept or refuse)"
                      if probe.teaches.startswith("class:") else "")
            return [Mistake("internal", answer.reason + broken, where)]
        if BARE_CONSTANT.search(answer.reason):
            return [Mistake("nan-token", answer.reason, where)]
        return [Mistake("malformed", answer.reason, where)]
    if answer.kind != "ok":
        return None
    if request.op == "decode" and probe.teaches.startswith("class:") and result.verdict is Verdict.ADAPTER_ERROR:
        found = _header_missing(probe.case.data.get("message"), answer.message, where)
        if found:
            return found
    if request.op == "decode" and probe.teaches in FEATURES:
        found = _decoded(kind, probe, answer.message, edition, where)
        if found or result.verdict is not Verdict.ADAPTER_ERROR:
            return found or None
    if result.verdict is Verdict.ADAPTER_ERROR:
        return [Mistake("malformed", result.detail, where)]
    return None


def _held(kind, probe: Probe, request: Request, answer: Answer, edition: str) -> str | None:
    """What the frame an encode probe was answered with holds where it differs from the request, read by the
    reference codec (e.g. "Announce.height: the request gave 'nan:7fc00001', the frame holds 'nan'"), or None."""
    data = probe.case.data
    try:
        held = kind.codec.decode(answer.frame, request.encoding, data, edition)
        diffs = kind.codec.differences(data["message"], held, True, edition)
    except (ValueError, KeyError, TypeError, AttributeError):
        return None
    held = "; ".join(f"{d.path}: the request gave {d.expected!r}, the frame holds {d.actual!r}" for d in diffs[:3])
    return held or None


def _decoded(kind, probe: Probe, message, edition: str, where: str) -> list[Mistake]:
    """The mistakes a decoded answer shows: header fields left out, values a JSON writer got wrong."""
    data = probe.case.data
    expected = data["message"]
    out = _header_missing(expected, message, where)
    try:
        diffs = kind.codec.differences(expected, message, data.get("compare", {}).get("nan_payload", False), edition)
    except (TypeError, ValueError, KeyError, AttributeError):
        return out
    for diff in diffs:
        code = value_mistake(diff.expected, diff.actual)
        if code is not None:
            out.append(Mistake(code, f"{diff.path}: expected {diff.expected!r}, answered {diff.actual!r}", where))
    return out


def _header_missing(expected, message, where: str) -> list[Mistake]:
    """The header fields the case's message has that a decoded answer left out."""
    if isinstance(message, dict) and isinstance(message.get("header"), dict) and isinstance(expected, dict) \
            and isinstance(expected.get("header"), dict):
        missing = [k for k in expected["header"] if k not in message["header"]]
        if missing:
            return [Mistake("header-missing", f"no {', '.join(missing)} in {str(message['header'])[:120]}", where)]
    return []


def _no_header(kind, probe: Probe, request: Request, answer: Answer, edition: str, out: Outcome) -> list[Mistake]:
    """An encode request whose header gives no field: encoded with the implementation's defaults, or a mistake."""
    where = f"encode of {probe.case.id} with \"header\": {{}}"
    if answer.kind == "unsupported":
        return []
    if answer.reason.startswith(GAVE_UP):  # the session gave up on a program dying on the probes before it
        out.findings.append(f"{where}: {answer.kind}: {answer.reason}")
        return []
    if answer.kind != "ok":
        return [Mistake("header-absent", f"{answer.kind}: {answer.reason}", where)]
    try:
        kind.codec.decode(answer.frame, request.encoding, probe.case.data, edition)
    except (ValueError, KeyError, TypeError) as exc:
        out.findings.append(f"{where}: encoded to a frame the reference codec refuses ({exc})")
        return []
    out.passed.append("an encode request without header fields encoded with the implementation's defaults")
    return []

"""Judging a capture into the one result model: every datagram on the suite's ports is a frame the suite's
rules judge, every watched frame feeds the exchange rules; findings are tallied per group and case, each case
listing its first failing frames (a capture of a million frames gives a report of a few pages). Sans-IO: the
caller reads the capture and feeds its records."""

from __future__ import annotations

import datetime as dt
from collections import Counter
from dataclasses import dataclass, field

from ..core.results import CaseResult, CheckResult, MessageResult, RunResult, message_verdict
from ..core.verdicts import Verdict, worst
from ..core.wording import counted
from .clocks import CHOOSE, CHOOSE_BYTES, CLOCK_BACK, CLOCK_JUMP, CONFIRM, NEVER, LogClocks
from .datagrams import Datagram, Dissector, describe_linktype
from .findings import CaptureRules, Finding, Watched
from .logs import Logged
from .outside import Outside
from .recording import DAMAGED, OWN, RECEIVED
from .records import Record

FRAME_CLAUSE = "the byte rules of the suite's corpus (rules.json)"
RECENT = 256  # watched frames remembered to recognise a datagram the network duplicated


@dataclass
class Selection:
    """What part of a capture is judged: ports (None: the suite's usual ones), groups, addresses (an IP
    address or a system id), and a window of seconds from the first record."""

    ports: frozenset[int] | None = None
    groups: frozenset[str] = frozenset()
    src: str | int | None = None
    dst: str | int | None = None
    host: str | int | None = None
    start: float | None = None
    end: float | None = None
    listed: int = 20  # failing frames listed per case
    scale: float = 1.0  # multiplies the exchanges' time bounds


@dataclass
class _Tally:
    clause: str
    counts: Counter = field(default_factory=Counter)
    listed: list = field(default_factory=list)
    first: int | None = None
    last: int | None = None


class CaptureJudge:
    def __init__(self, suite_name: str, rules: CaptureRules, edition: str, selection: Selection, log: bool = False):
        self.suite, self.rules, self.edition, self.selection = suite_name, rules, edition, selection
        self.ports = selection.ports or rules.ports
        self.dissector = Dissector()
        self.tracker = rules.exchanges(edition, selection.scale)
        self.tallies: dict[tuple[str, str], _Tally] = {}
        self.skipped: Counter = Counter()  # records and datagrams not judged, by why
        self.outside = Outside()  # frames of messages outside the suite, by message
        self.origin: float | None = None
        self.last: float = 0.0
        self.records = self.datagrams = 0
        self.valid: dict[str, list[int]] = {}  # group -> [valid frames, first, last]
        self.source = ""  # the file being judged, when there are several
        self.sources: set[str] = set()
        self.corpus_limit = 0  # distinct frames kept to replay through an implementation (pcap --adapter)
        self.corpus: dict[bytes, tuple[str, int]] = {}  # frame -> (group, its first frame number)
        self.corpus_left = 0  # distinct frames beyond the limit
        self.recent: dict[bytes, None] = {}  # the last watched frames, oldest first, to tell duplicates
        self.duplicates = 0
        self.about: dict | None = None  # the recorded run the capture holds (run --pcap), if any
        self.keep_commented = False  # keep the datagrams that carry a comment (a recorded run, to replay)
        self.recording_complete = False  # the recorded run ended (it was not interrupted, the file is whole)
        self.flood: float | None = None  # when a recorded run's robustness phase began
        self.commented: list[Datagram] = []
        self.groups = selection.groups
        self.filtered = any(v is not None for v in (selection.src, selection.dst, selection.host, selection.start,
                                                    selection.end))
        self.plain = not self.filtered and not self.groups  # nothing narrows the frames judged
        self.lost = 0  # datagrams the watcher lost before it could read them (the kernel dropped them)
        self.log = log  # the frames come from logs (``logged``), not from datagrams
        self.clocks = LogClocks(self.tracker, self._observe, self._due, self._split) if log else None
        self.tick = self.clocks.tick if log else None  # a log's frame's time on its clock (the hot path: bound once)
        self.waiting: list | None = [] if log else None  # a log's first frames, until its logging system is chosen
        self.waiting_bytes = 0
        self.across = 0  # exchanges open across a split of a log

    def losses(self, start: float, end: float, count: int) -> None:
        """``count`` datagrams were lost between ``start`` and ``end`` (a live watcher's receive buffer)."""
        self.lost += count
        self.tracker.lost(start, end)

    def feed(self, record: Record, source: str = "") -> None:
        """Judge one record; ``source`` names its file in reports (several files judged at once)."""
        self._saw(record.time)
        got = self.dissector.datagram(record)
        if got.__class__ is str:
            self.skipped[got if not got.startswith("link type") else f"{describe_linktype(record.linktype)}: "
                         "not Ethernet, raw IP, Linux cooked capture or BSD loopback"] += 1
            return
        self._judge_datagram(got, source)

    def received(self, got: Datagram, frames: bool = True) -> None:
        """Judge a datagram a socket received (each is a record of its own); ``frames=False``: follow the exchanges
        through it without judging its frame (a relay's side judges the frames that side sent, not those it got)."""
        self._saw(got.time)
        self._judge_datagram(got, frames=frames)

    def _saw(self, t: float) -> None:
        """Count a record seen at time ``t``: the capture's first and last times."""
        self.records += 1
        if self.origin is None:
            self.origin = t
        if t > self.last:
            self.last = t

    def logged(self, got: Logged, source: str = "") -> None:
        """Judge one frame of a log (``source`` names its file when there are several). A log records no time of
        reception: its frames are timed on the logging system's clock (``clocks.LogClocks``), chosen among its first
        frames, which are held until then."""
        waiting = self.waiting
        if waiting is not None:
            waiting.append((got, source))
            self.waiting_bytes += len(got.payload)
            if len(waiting) >= CHOOSE or self.waiting_bytes >= CHOOSE_BYTES:
                self._choose()
            return
        got.time = self.tick(got.system, got.time)
        self.records += 1
        if source is not self.source or not self.sources:
            self._from(source)
        if self.filtered and not self._in(got, frames=False):
            self.skipped["outside the selection"] += 1
            return
        self._judge_unit(got, False, got.channel)

    def _choose(self) -> None:
        """Choose a log's logging system among its first frames, and judge them."""
        waiting, self.waiting = self.waiting, None
        self.clocks.choose([got for got, _ in waiting])
        self.origin, self.last = self.clocks.origin, self.clocks.now
        for got, source in waiting:
            self.logged(got, source)

    def _observe(self, w: Watched) -> None:
        """Follow the exchanges through a watched frame."""
        self._tally_selected(self.tracker.observe(w))

    def _due(self, now: float) -> None:
        """Judge the exchanges whose bound passed by ``now`` on a log's clock (it runs on every frame)."""
        self._tally_selected(self.tracker.due(now))

    def _split(self) -> None:
        """The log's clock jumped: a new stretch begins, and the exchanges open are closed."""
        findings, count = self.tracker.split("the log's clock jumped meanwhile")
        self._tally_selected(findings)
        self.across += count

    def _tally_selected(self, findings) -> None:
        """Tally the findings of the messages the selection holds (all, where it names none)."""
        for finding in findings:
            if not self.groups or finding.group in self.groups:
                self._tally(finding)

    def found(self, f: Finding, source: str = "") -> None:
        """Tally what a log says of its frames (a bag connection's definition), as it is found."""
        self._from(source)
        self._tally_selected((f,))

    def _from(self, source: str) -> None:
        """Note that what follows comes from the file ``source`` names (several files judged at once)."""
        if source != self.source or not self.sources:
            self.source = source
            self.sources.add(source)

    def _judge_datagram(self, got: Datagram, source: str = "", frames: bool = True) -> None:
        """Judge one UDP datagram of a record (``feed``) or of a socket (``received``)."""
        self._from(source)
        recorded = got.comment is not None and self.keep_commented  # a datagram of a recorded run: on its ports
        # what a recorded run's robustness phase sent on purpose (corpus frames, garbage, probes): its frames are
        # not the node's to judge, but the node answers its requests
        deliberate = recorded and got.comment not in (RECEIVED, OWN) and got.comment.split(" ", 1)[0] not in \
            self.about["cases"]
        if recorded and not deliberate:
            self.commented.append(got)
        if deliberate and self.flood is None:
            self.flood = got.time  # from here on the node answers the flood: no exchanges to follow
        if not recorded and got.sport not in self.ports and got.dport not in self.ports:
            self.skipped["UDP on other ports"] += 1
            return
        if self.filtered and not self._in(got, frames=False):  # outside the window or the host: unseen
            self.skipped["outside the selection"] += 1
            return
        if recorded and got.comment.endswith(DAMAGED):  # a scenario's invalid frame: the node's answer is judged
            self.skipped["frames a scenario of the recorded run damaged on purpose"] += 1
            return
        self._judge_unit(got, deliberate, frames=frames)

    def _judge_unit(self, got: Datagram | Logged, deliberate: bool, channel=None, frames: bool = True) -> None:
        """Judge the frame a datagram or a log holds (``channel``: what judges a logged frame that does not name its
        message; ``frames=False``: only follow the exchanges through it), and follow the exchanges through it."""
        frame = self.rules.frame(got.payload) if channel is None else channel.frame(got.payload)
        if not frames:
            if frame is not None and frame.fields is not None and frame.rule is None and self.flood is None:
                self._exchanges(got, frame)
            return
        if self.plain and frame is not None and frame.rule is None and frame.fields is None and not deliberate \
                and not got.cut and not self.corpus_limit:
            valid = self.valid.get(frame.group)  # the common case: a valid frame no exchange, filter or corpus needs
            if valid is not None:
                self.datagrams += 1
                valid[0] += 1
                valid[2] = got.number
                return
        if deliberate:
            self.skipped["datagrams the session sent on purpose in its robustness phase"] += 1
        elif frame is None:
            self.skipped["datagrams on the ports that are not frames of the suite"] += 1
        elif frame.group is None:
            self.outside.add(frame.outside, frame.undefined)
        if frame is None or frame.group is None:
            return
        group = frame.group
        if self.filtered and not self._addressed(frame.src, frame.dst, frames=False):
            self.skipped["outside the selection"] += 1
            return
        # --src, --dst and --message narrow the frames judged; the exchanges are followed through all the rest
        shown = (not self.groups or group in self.groups) and (not self.filtered or (
            self._in(got, frames=True) and self._addressed(frame.src, frame.dst, frames=True)))
        if shown and not deliberate:
            self._judge_frame(group, frame, got)
        elif not deliberate:
            self.skipped["outside the selection"] += 1
        if frame.fields is not None and frame.rule is None and not got.cut and self.flood is None:
            self._exchanges(got, frame)

    def _exchanges(self, got: Datagram | Logged, frame) -> None:
        """Follow the exchanges through a valid frame an exchange watches."""
        watched = Watched(got.number, got.time, frame.group, frame.fields, frame.src, frame.dst, got)
        if got.payload in self.recent:  # the network duplicated it: one frame for the exchanges
            self.duplicates += 1
            self.tracker.again(watched)
            return
        self.recent[got.payload] = None
        if len(self.recent) > RECENT:
            del self.recent[next(iter(self.recent))]
        if self.clocks is None:
            self._observe(watched)
        else:
            self.clocks.watch(watched)

    def _judge_frame(self, group: str, frame, got: Datagram | Logged) -> None:
        """Tally a frame's verdict (and keep it for the corpus an adapter decodes)."""
        self.datagrams += 1
        if self.corpus_limit and not got.cut and got.payload not in self.corpus:
            if len(self.corpus) < self.corpus_limit:
                self.corpus[got.payload] = (group, got.number)
            else:
                self.corpus_left += 1
        if got.cut:
            self._tally(Finding(group, "frame/truncated-by-capture", Verdict.INCONCLUSIVE, FRAME_CLAUSE,
                                f"{len(got.payload)} bytes captured: the capture's snaplen cut the datagram",
                                got.number, got.time, got.payload, got))
        elif frame.rule is not None:
            self._tally(Finding(group, f"frame/{frame.rule}", Verdict.INCONCLUSIVE if frame.undecided else Verdict.FAIL,
                                frame.clause, f"byte {frame.offset}: {frame.detail}", got.number, got.time,
                                got.payload, got))
        else:
            valid = self.valid.get(group)
            if valid is None:
                self.valid[group] = [1, got.number, got.number]
            else:
                valid[0] += 1
                valid[2] = got.number

    def result(self, *, implementation: str, started: str, duration: float, strict: bool, title: str,
               notes: list[str] = (), complete: bool = True, until: float | None = None) -> RunResult:
        """The run result; ``until``: when watching ended (default: the last record, or the window's end)."""
        if self.waiting is not None:
            self._choose()
        if self.clocks is not None:
            self.clocks.end()
            self.last = self.clocks.now
        end = self.last if until is None else max(self.last, until)
        if self.selection.end is not None and self.origin is not None:
            end = min(end, self.origin + self.selection.end)
        if self.flood is not None:
            end = min(end, self.flood)
        self._tally_selected(self.tracker.finish(end))
        for group, (n, first, last) in self.valid.items():
            tally = self.tallies.setdefault((group, "frame/valid"), _Tally(FRAME_CLAUSE))
            tally.counts[Verdict.PASS] += n
            tally.first, tally.last = first, last
        groups: dict[str, list[CaseResult]] = {}
        for (group, case), tally in sorted(self.tallies.items()):
            groups.setdefault(group, []).append(self._case(group, case, tally))
        messages = [MessageResult(name, self.rules.keys.get(name, "-"), message_verdict(cases, strict), cases)
                    for name, cases in self._in_order(groups)]
        return RunResult(self.suite, title, self.edition, implementation, "capture", strict, started, duration,
                         messages, "", list(notes) + self.notes(), complete)

    def standing(self) -> list[tuple[str, int, int, int]]:
        """So far, per group: (group, valid frames, invalid frames, failed exchange observations)."""
        rows: dict[str, list[int]] = {g: [n, 0, 0] for g, (n, _, _) in self.valid.items()}
        for (group, case), tally in self.tallies.items():
            bad = sum(n for v, n in tally.counts.items() if v is not Verdict.PASS)
            row = rows.setdefault(group, [0, 0, 0])
            row[1 if case.startswith("frame/") else 2] += bad
        return [(g, *row) for g, row in self._in_order(rows)]

    def _in_order(self, by_group: dict) -> list[tuple]:
        """The items of a dict by group, in the suite's order of its groups."""
        order = {name: i for i, name in enumerate(self.rules.keys)}
        return sorted(by_group.items(), key=lambda kv: (order.get(kv[0], len(order)), kv[0]))

    def notes(self) -> list[str]:
        jumps = self.clocks.jumps if self.clocks is not None else 0
        span = f", from {_when(self.origin)}" + ("" if jumps else f" for {self.last - self.origin:.3f} s") \
            if self.origin else ""  # a log split by its clock's jumps spans no one stretch of time
        if self.log:
            out = [f"{counted(self.records, 'frame', grouped=True)} read, {self.datagrams:,} judged{span}"]
        else:
            out = [f"{self.records:,} records, {self.datagrams:,} datagrams on the ports judged{span}"]
        out += self.outside.notes(self.rules.outside)
        if not self.tallies and not self.valid:
            out.append("no frame of the suite was judged: none in the selection" if self.log else
                       "no frame of the suite was judged: none on the ports (--port names others) or in the selection")
        out += [f"{n:,} not judged: {why}" for why, n in self.skipped.most_common()]
        if self.lost:
            out.append(f"{self.lost:,} datagrams were dropped by the kernel before they could be read (a flood, or a "
                       "receive buffer too small): not judged, and an exchange left unanswered meanwhile is INCONCLUSIVE")
        if self.flood is not None:
            out.append(f"the exchanges are followed until the recorded run's robustness phase began, "
                       f"{self.flood - self.origin:.3f} s in (its flood and the node's answers to it are not exchanges)")
        if self.duplicates:
            out.append(f"{self.duplicates:,} frames identical to one shortly before were judged once by the exchange "
                       "rules" if self.log else f"{self.duplicates:,} datagrams identical to one shortly before "
                       "(duplicated by the network) were judged once by the exchange rules")
        if self.clocks is not None:
            out += self.clocks.notes()
        if jumps:
            out.append(f"the log's clock jumped {counted(jumps, 'time', grouped=True)} (ahead by more than "
                       f"{CLOCK_JUMP:g} s or back by more than {CLOCK_BACK:g} s, the logging system's frames running on "
                       f"from there for {CONFIRM:g} s: a gap in the log, its clock set), splitting it into "
                       f"{jumps + 1:,} stretches timed apart: what was due before a jump judged, "
                       f"{counted(self.across, 'exchange', grouped=True)} open across a split INCONCLUSIVE")
        if self.dissector.held or self.dissector.given_up:
            out.append(f"{len(self.dissector.held) + self.dissector.given_up:,} IP datagrams never reassembled "
                       "(fragments missing from the capture)")
        return out

    # ------------------------------------------------------------ tallies and cases

    def _tally(self, f: Finding) -> None:
        tally = self.tallies.get((f.group, f.case))
        if tally is None:
            tally = self.tallies[(f.group, f.case)] = _Tally(f.clause)
        tally.counts[f.verdict] += 1
        if f.number is not None:
            tally.first = f.number if tally.first is None else tally.first
            tally.last = f.number
        if f.verdict is not Verdict.PASS and len(tally.listed) < self.selection.listed:
            f.where = _place(f.where, self.source)
            tally.listed.append(f)
            tally.clause = f.clause

    def _case(self, group: str, case: str, tally: _Tally) -> CaseResult:
        noun = case.split("/", 1)[0]  # frame, exchange, connection
        checks = [CheckResult("count", verdict, f"{n:,} {noun}{'s' if n != 1 else ''}" + (
            f" (frames {tally.first} to {tally.last})" if verdict is Verdict.PASS and tally.first
            and len(self.sources) == 1 else ""))
                  for verdict, n in sorted(tally.counts.items(), key=lambda kv: kv[0].value)]
        for f in tally.listed:
            at = f"at {f.time - self.origin:.6f} s, " if f.time is not None and self.origin is not None and \
                abs(f.time) != NEVER else "" if f.label else "at -, "  # NEVER: a log's frame before its clock began
            checks.append(CheckResult(f.label or f"frame {f.number}", f.verdict, f"{at}{f.where}: {f.detail}".rstrip(": "),
                                      actual=f.frame[:512].hex() if f.frame is not None else None, clause=f.clause))
        bad = sum(n for v, n in tally.counts.items() if v is not Verdict.PASS)
        if bad > len(tally.listed):
            checks.append(CheckResult("more", worst(tally.counts), f"{bad - len(tally.listed):,} more not listed "
                                                                   f"(--list-frames raises the cap)"))
        rule = case.split("/")[1] if case.startswith("frame/") and case != "frame/valid" else None
        return CaseResult(f"{self.suite}/{group}/capture/{case}", group, worst(tally.counts), None, tally.clause,
                          checks, rule)

    def _in(self, d: Datagram | Logged, frames: bool) -> bool:
        """Whether a datagram or a logged frame is within the window, and a datagram from or to the host (and, for
        ``frames``, from --src and to --dst, where those are addresses: a log has none)."""
        s = self.selection
        if s.start is not None and self.origin is not None and d.time - self.origin < s.start:
            return False
        if s.end is not None and self.origin is not None and d.time - self.origin > s.end:
            return False
        if d.__class__ is Logged:
            return True
        wanted = ((s.host, (d.src, d.dst)),) + (((s.src, (d.src,)), (s.dst, (d.dst,))) if frames else ())
        return all(not isinstance(want, str) or want in have for want, have in wanted)

    def _addressed(self, src: int | None, dst: int | None, frames: bool) -> bool:
        """The same, where the host, --src or --dst are system ids."""
        s = self.selection
        wanted = ((s.host, (src, dst)),) + (((s.src, (src,)), (s.dst, (dst,))) if frames else ())
        return all(not isinstance(want, int) or want in have for want, have in wanted)


def _place(d: Datagram | Logged | str, source: str) -> str:
    """Where a datagram went (``[file ]src:port → dst:port``), where a logged frame is, or what a log's own text says."""
    if isinstance(d, str):
        return f"{source}{d}"
    if d.__class__ is Logged:
        return d.place(source)
    host = lambda a: f"[{a}]" if ":" in a else a  # noqa: E731
    return f"{source}{host(d.src)}:{d.sport} → {host(d.dst)}:{d.dport}"


def _when(t: float) -> str:
    try:
        return dt.datetime.fromtimestamp(t, dt.timezone.utc).isoformat(timespec="microseconds")
    except (OverflowError, ValueError, OSError):  # a damaged or odd timestamp: no calendar date holds it
        return f"{t:.6f} s after 1970"



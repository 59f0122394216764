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
from .datagrams import Datagram, Dissector, describe_linktype
from .findings import CaptureRules, Finding, Watched
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
    def __init__(self, suite_name: str, rules: CaptureRules, edition: str, selection: Selection):
        self.suite, self.rules, self.edition, self.selection = suite_name, rules, edition, selection
        self.ports = selection.ports or rules.ports
        self.dissector = Dissector()
        self.tracker = rules.exchanges(edition, selection.scale)
        self.tallies: dict[tuple[str, str], _Tally] = {}
        self.skipped: Counter = Counter()  # records and datagrams not judged, by why
        self.outside: Counter = Counter()  # frames of messages outside the suite, by message
        self.origin: float | None = None
        self.last: float = 0.0
        self.records = self.datagrams = 0
        self.valid: dict[str, list[int]] = {}  # group -> [valid frames, first, last]
        self.source = ""  # the file being judged, when there are several
        self.corpus_limit = 0  # distinct frames kept to replay through an implementation (pcap --adapter)
        self.corpus: dict[bytes, tuple[str, int]] = {}  # frame -> (group, its first frame number)
        self.corpus_left = 0  # distinct frames beyond the limit
        self.recent: dict[bytes, None] = {}  # the last watched frames, oldest first, to tell duplicates
        self.duplicates = 0
        self.about: dict | None = None  # the recorded run the capture holds (run --pcap), if any
        self.keep_commented = False  # keep the datagrams that carry a comment (a recorded run, to replay)
        self.commented: list[Datagram] = []
        self.groups = selection.groups
        self.filtered = any(v is not None for v in (selection.src, selection.dst, selection.host, selection.start,
                                                    selection.end))

    def feed(self, record: Record, source: str = "") -> None:
        """Judge one record; ``source`` names its file in reports (several files judged at once)."""
        self.records += 1
        if self.origin is None:
            self.origin = record.time
        if record.time > self.last:
            self.last = record.time
        got = self.dissector.datagram(record)
        if got.__class__ is str:
            self.skipped[got if not got.startswith("link type") else f"{describe_linktype(record.linktype)}: "
                         "not Ethernet, raw IP, Linux cooked capture or BSD loopback"] += 1
            return
        self.feed_datagram(got, source)

    def feed_datagram(self, got: Datagram, source: str = "") -> None:
        """Judge one UDP datagram (one a socket received, or one found in a record)."""
        if self.origin is None:
            self.origin = got.time
        if got.time > self.last:
            self.last = got.time
        self.source = source
        recorded = got.comment is not None and self.keep_commented  # a datagram of a recorded run: on its ports
        if recorded:
            self.commented.append(got)
        if not recorded and got.sport not in self.ports and got.dport not in self.ports:
            self.skipped["UDP on other ports"] += 1
            return
        if self.filtered and not self._selected(got):
            self.skipped["outside the selection"] += 1
            return
        self.datagrams += 1
        frame = self.rules.frame(got.payload)
        if frame is None:
            self.skipped["datagrams on the ports that are not frames of the suite"] += 1
            return
        group = frame.group
        if group is None:
            self.outside[frame.outside] += 1
            return
        if self.filtered and not self._addressed(frame.src, frame.dst):
            self.skipped["outside the selection"] += 1
            return
        if (self.corpus_limit and not got.cut and (not self.groups or group in self.groups)
                and got.payload not in self.corpus):
            if len(self.corpus) < self.corpus_limit:
                self.corpus[got.payload] = (group, got.number)
            else:
                self.corpus_left += 1
        if self.groups and group not in self.groups:
            self.skipped["outside the selection"] += 1
        elif got.cut:
            self._tally(Finding(group, "frame/truncated-by-capture", Verdict.INCONCLUSIVE, FRAME_CLAUSE,
                                f"{len(got.payload)} bytes captured: the capture's snaplen cut the datagram",
                                got.number, got.time, got.payload, got))
        elif frame.rule is not None:
            self._tally(Finding(group, f"frame/{frame.rule}", Verdict.FAIL, frame.clause,
                                f"byte {frame.offset}: {frame.detail}", got.number, got.time, got.payload, got))
        else:
            valid = self.valid.get(group)
            if valid is None:
                self.valid[group] = [1, got.number, got.number]
            else:
                valid[0] += 1
                valid[2] = got.number
        if frame.fields is not None and frame.rule is None and not got.cut:
            if got.payload in self.recent:  # the network duplicated it: one frame for the exchanges
                self.duplicates += 1
                return
            self.recent[got.payload] = None
            if len(self.recent) > RECENT:
                del self.recent[next(iter(self.recent))]
            for finding in self.tracker.observe(Watched(got.number, got.time, group, frame.fields,
                                                        frame.src, frame.dst, got)):
                if not self.groups or finding.group in self.groups:
                    self._tally(finding)

    def result(self, *, implementation: str, started: str, duration: float, strict: bool, title: str,
               notes: list[str] = (), complete: bool = True) -> RunResult:
        for finding in self.tracker.finish(self.last):
            if not self.selection.groups or finding.group in self.selection.groups:
                self._tally(finding)
        for group, (n, first, last) in self.valid.items():
            tally = self.tallies.setdefault((group, "frame/valid"), _Tally(FRAME_CLAUSE))
            tally.counts[Verdict.PASS] += n
            tally.first, tally.last = first, last
        groups: dict[str, list[CaseResult]] = {}
        for (group, case), tally in sorted(self.tallies.items()):
            groups.setdefault(group, []).append(self._case(group, case, tally))
        order = list(self.rules.keys)
        messages = [MessageResult(name, self.rules.keys.get(name, "-"), message_verdict(cases, strict), cases)
                    for name, cases in sorted(groups.items(), key=lambda kv: (
                        order.index(kv[0]) if kv[0] in order else len(order), kv[0]))]
        return RunResult(self.suite, title, self.edition, implementation, "capture", strict, started, duration,
                         messages, "", list(notes) + self.notes(), complete)

    def standing(self) -> list[tuple[str, int, int, int]]:
        """So far, per group: (group, valid frames, invalid frames, failed exchange observations)."""
        rows: dict[str, list[int]] = {g: [n, 0, 0] for g, (n, _, _) in self.valid.items()}
        for (group, case), tally in self.tallies.items():
            bad = sum(n for v, n in tally.counts.items() if v is not Verdict.PASS)
            row = rows.setdefault(group, [0, 0, 0])
            row[1 if case.startswith("frame/") else 2] += bad
        order = list(self.rules.keys)
        return [(g, *row) for g, row in sorted(rows.items(), key=lambda kv: (
            order.index(kv[0]) if kv[0] in order else len(order), kv[0]))]

    def notes(self) -> list[str]:
        out = [f"{self.records:,} records, {self.datagrams:,} datagrams on the ports judged"
               + (f", from {_when(self.origin)} for {self.last - self.origin:.3f} s" if self.origin else "")]
        if self.outside:
            top = ", ".join(f"{name} ({n:,})" for name, n in self.outside.most_common(8))
            out.append(f"{sum(self.outside.values()):,} frames of {len(self.outside)} messages the suite does not "
                       f"cover (framing checked only): {top}{' ...' if len(self.outside) > 8 else ''}")
        out += [f"{n:,} not judged: {why}" for why, n in self.skipped.most_common()]
        if self.duplicates:
            out.append(f"{self.duplicates:,} datagrams identical to one shortly before (duplicated by the network) "
                       "were judged once by the exchange rules")
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
        noun = "frame" if case.startswith("frame/") else "exchange"
        checks = [CheckResult("count", verdict, f"{n:,} {noun}{'s' if n != 1 else ''}" + (
            f" (frames {tally.first} to {tally.last})" if verdict is Verdict.PASS and tally.first else ""))
                  for verdict, n in sorted(tally.counts.items(), key=lambda kv: kv[0].value)]
        for f in tally.listed:
            at = f"{f.time - self.origin:.6f} s" if f.time is not None and self.origin is not None else "-"
            checks.append(CheckResult(f"frame {f.number}", f.verdict, f"at {at}, {f.where}: {f.detail}".rstrip(": "),
                                      actual=f.frame[:512].hex() if f.frame is not None else None, clause=f.clause))
        bad = sum(n for v, n in tally.counts.items() if v is not Verdict.PASS)
        if bad > len(tally.listed):
            checks.append(CheckResult("more", worst(tally.counts), f"{bad - len(tally.listed):,} more not listed "
                                                                   f"(--list-frames raises the cap)"))
        rule = case.split("/")[1] if case.startswith("frame/") and case != "frame/valid" else None
        return CaseResult(f"{self.suite}/{group}/capture/{case}", group, worst(tally.counts), None, tally.clause,
                          checks, rule)

    def _selected(self, d: Datagram) -> bool:
        s = self.selection
        if s.start is not None and self.origin is not None and d.time - self.origin < s.start:
            return False
        if s.end is not None and self.origin is not None and d.time - self.origin > s.end:
            return False
        for want, have in ((s.src, (d.src,)), (s.dst, (d.dst,)), (s.host, (d.src, d.dst))):
            if isinstance(want, str) and want not in have:
                return False
        return True

    def _addressed(self, src: int | None, dst: int | None) -> bool:
        s = self.selection
        for want, have in ((s.src, (src,)), (s.dst, (dst,)), (s.host, (src, dst))):
            if isinstance(want, int) and want not in have:
                return False
        return True


def _place(d: Datagram, source: str) -> str:
    """Where a datagram went: ``[file ]src:port → dst:port``."""
    host = lambda a: f"[{a}]" if ":" in a else a  # noqa: E731
    return f"{source}{host(d.src)}:{d.sport} → {host(d.dst)}:{d.dport}"


def _when(t: float) -> str:
    try:
        return dt.datetime.fromtimestamp(t, dt.timezone.utc).isoformat(timespec="microseconds")
    except (OverflowError, ValueError, OSError):  # a damaged or odd timestamp: no calendar date holds it
        return f"{t:.6f} s after 1970"

"""JUnit XML for CI test views: one testsuite per message, one testcase per case.

FAIL and WAIVER_STALE (and NON_STRICT and INCONCLUSIVE under --strict) are failures; CRASH, TIMEOUT and
ADAPTER_ERROR are errors; UNSUPPORTED and a lenient INCONCLUSIVE are skipped; a scenario's timeline goes with it; WAIVED, IMPL_DEFINED and a lenient NON_STRICT pass with a note in
``<system-out>``. Implementation text is stripped of what XML 1.0 cannot carry; ElementTree escapes the rest.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections import Counter

from ..core.verdicts import Verdict, failing
from ..core.results import CaseResult, RunResult
from ..escaping import clean
from .common import cause_line, incident_lines, timeline_lines

ERRORS = {Verdict.CRASH, Verdict.TIMEOUT, Verdict.ADAPTER_ERROR}
MESSAGE_LIMIT = 500  # characters of detail in a failure's message attribute


def outcome(case: CaseResult, strict: bool) -> str | None:
    """``failure``, ``error``, ``skipped``, ``note`` (passed, with system-out) or None (plain pass)."""
    v = case.verdict
    if v in ERRORS:
        return "error"
    if failing(v, strict):
        return "failure"
    if v in (Verdict.UNSUPPORTED, Verdict.INCONCLUSIVE):
        return "skipped"
    return None if v is Verdict.PASS and not case.notes else "note"


def body(case: CaseResult, cause: str | None = None) -> str:
    """The full account of a case: detail, its cause, clause, rule, errata, waiver, and every check."""
    lines = [f"{case.verdict.value}: {case.detail}", *([f"cause: {cause}"] if cause else ()), f"clause: {case.clause}",
             *(f"note: {n}" for n in case.notes)]
    if case.rule:
        lines.append(f"rule: {case.rule}")
    if case.errata:
        lines.append(f"errata: {', '.join(case.errata)}")
    if case.waiver:
        lines.append(f"waiver: {case.waiver}")
    for k in case.checks:
        lines.append(f"{k.check} {k.verdict.value}: {k.detail}")
        if k.expected:
            lines += [f"  expected {k.expected}", f"  actual   {k.actual or '(none)'}"]
        lines += [f"  bytes {d.start}-{d.end - 1} = {d.field}" for d in k.diffs]
    if case.timeline:
        lines += ["timeline:", *(f"  {line}" for line in timeline_lines(case))]
    return clean("\n".join(lines))


def testcase(case: CaseResult, suite: str, message: str, strict: bool,
             cause: str | None = None) -> tuple[ET.Element, str | None]:
    el = ET.Element("testcase", classname=f"{suite}.{message}", name=clean(case.id), time="0")
    kind = outcome(case, strict)
    if kind == "note":
        ET.SubElement(el, "system-out").text = body(case, cause)
    elif kind == "skipped":
        ET.SubElement(el, "skipped", message=clean(case.detail)[:MESSAGE_LIMIT])
    elif kind:
        sub = ET.SubElement(el, kind, message=clean(case.detail)[:MESSAGE_LIMIT], type=case.verdict.value)
        sub.text = body(case, cause)
    return el, kind


def render_junit(result: RunResult) -> str:
    props = [("headline", result.headline()), ("suite", result.suite), ("edition", result.edition), ("implementation", result.implementation),
             ("adapter", result.adapter), ("strict", str(result.strict).lower()),
             ("complete", str(result.complete).lower()),
             *(("cause", cause_line(c)) for c in result.cause_groups()),
             *(("incident", line) for line in incident_lines(result)), *(("note", note) for note in result.notes)]
    titles = {case_id: c.title for c in result.cause_groups() for case_id in c.cases}
    suites = []
    for message in result.messages:
        cases = [testcase(c, result.suite, message.name, result.strict, titles.get(c.id)) for c in message.cases]
        kinds = Counter(kind for _, kind in cases)
        counts = {"tests": len(cases), "failures": kinds["failure"], "errors": kinds["error"], "skipped": kinds["skipped"]}
        suite = ET.Element("testsuite", name=f"{result.suite}/{message.name}", **{k: str(n) for k, n in counts.items()},
                           time="0", timestamp=result.started)
        properties = ET.SubElement(suite, "properties")
        for name, value in props:
            ET.SubElement(properties, "property", name=name, value=clean(value))
        suite.extend(el for el, _ in cases)
        suites.append((suite, counts))
    totals = {k: str(sum(counts[k] for _, counts in suites)) for k in ("tests", "failures", "errors", "skipped")}
    root = ET.Element("testsuites", name=clean(f"imc-conformance {result.suite} {result.edition}: {result.implementation}"), **totals,
                      time=f"{result.duration:.3f}")
    root.extend(suite for suite, _ in suites)
    if result.stderr:
        holder = root[0] if len(root) else root
        ET.SubElement(holder, "system-err").text = clean(result.stderr)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"

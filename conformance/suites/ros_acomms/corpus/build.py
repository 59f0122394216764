"""Rebuild the ros_acomms corpus: one vector file per type, and the coverage table, deterministically.

``imc-conformance generate --suite ros_acomms`` writes ``vectors/ros_acomms/cases/*.json``,
``vectors/ros_acomms/coverage.md``, the provenance of every rule and class (``provenance.md``) and the behavioural
coverage of its scenarios, ``vectors/ros_acomms/behaviour-coverage.md``; ``--check`` only reports drift. Both first
prove the corpus (the lint of its rules' sources, the one-flaw oracle); a corpus that fails them is not written. A type whose definition is the same in
every edition it exists in has one set of cases; otherwise each edition gets its own, under an id segment
naming the edition (``ros_acomms/SST/9.0.0/...``).
"""

from __future__ import annotations

import argparse
import copy
import json
import struct
import sys
from collections import Counter, defaultdict

from ....fuzz import promote
from ....fuzz.promote import promoted_cases
from ....kinds.scenario.coverage import coverage_markdown as behaviour_markdown, live_cases
from ....kinds.vector.provenance import case_documents, proven, provenance_markdown
from .. import codec
from ..definitions import PRIMITIVES, Edition, FieldType, Message, RosDefinitions, TypeDef, load_definitions
from ..fuzzing import RosFuzzSource
from ..msgtext import full_text, md5, service_md5
from ... import load_suite
from ...data_suite import write_generated
from ..paths import ros_data
from . import values
from .oracle import corpus_problems, flaws
from .rules import klass, outcomes, rules_document

FORMAT_VERSION = 1
ENC = "ros1"
CODEC = [f"encode-{ENC}", f"decode-{ENC}", "roundtrip"]
DECODE = [f"decode-{ENC}"]
# Why an invalid case breaks more rules than its own (flaws.why, by family).
WHY = {
    "truncated": "The bytes end inside a field: the fields after it are missing too.",
    "length-overrun": "A length reaching past the bytes left leaves none for the fields after it.",
}
SERIALIZATION = "ros-acomms#ros-1-serialization"
CHECKSUMS = "ros-acomms#ros-1-md5-checksums"
MIN_VALID = 4


def load_rules() -> list[dict]:
    return rules_document()["rules"]


def reference_of(name: str) -> str:
    return klass(name)["reference"]


def load_examples() -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = defaultdict(list)
    for example in json.loads(ros_data("examples.json").read_text(encoding="utf-8"))["examples"]:
        out[example["message"]["type"]].append(example)
    return out


class TypeCases:
    """Collects the cases of one type's vector file, keeping ids unique."""

    def __init__(self, defs: RosDefinitions, t: TypeDef, clauses: dict[str, str]):
        self.defs, self.t, self.clauses = defs, t, clauses
        self.cases: list[dict] = []

    def add(self, path: str, *, expect, clause: str, checks: list[str], tags: list[str], edition: Edition,
            frame: bytes | None = None, message: dict | None = None, **extra) -> None:
        case_id = f"ros_acomms/{self.t.name}/{path}"
        if any(c["id"] == case_id for c in self.cases):
            raise ValueError(f"duplicate case id {case_id}")
        record = {"id": case_id, "expect": expect, "clause": clause, "type": self.t.full,
                  "md5": md5(edition, edition[self.t.full]), "checks": checks}
        if frame is not None:
            record["frames"] = {ENC: frame.hex()}
        if message is not None:
            record["message"] = message
        record.update({k: v for k, v in extra.items() if v is not None})
        record["tags"] = sorted(set(tags))
        self.cases.append(record)


def expect_in(defs: RosDefinitions, editions: list[str], verdict: str):
    return verdict if editions == list(defs.editions) else {e: verdict for e in editions}


def build_type(defs: RosDefinitions, t: TypeDef, examples: list[dict], clauses: dict[str, str]) -> list[dict]:
    tc = TypeCases(defs, t, clauses)
    present = [e for e in defs.editions if t.in_edition(e)]
    by_text: dict[str, list[str]] = defaultdict(list)  # the codec cases of editions with the same definition
    by_description: dict[tuple, list[str]] = defaultdict(list)
    for name in present:
        edition = defs.edition(name)
        by_text[full_text(edition, edition[t.full])].append(name)
        by_description[tuple(description(edition, t).items())].append(name)
    for editions in by_text.values():
        prefix = "" if defs.editions[0] in editions else f"{editions[0]}/"
        codec_cases(tc, defs.edition(editions[0]), prefix, lambda v, eds=editions: expect_in(defs, eds, v), examples)
    for key, editions in by_description.items():
        prefix = "" if defs.editions[0] in editions else f"{editions[0]}/"
        tc.add(f"{prefix}definition", expect=expect_in(defs, editions, "valid"), clause=CHECKSUMS, checks=["describe"],
               tags=["definition"], edition=defs.edition(editions[0]), describe=dict(key))
    return tc.cases


def description(edition: Edition, t: TypeDef) -> dict:
    """What an implementation must say of the type: its MD5 and full definition text (and its service's MD5)."""
    out = {"md5": md5(edition, edition[t.full]), "definition": full_text(edition, edition[t.full])}
    halves = [f"{t.package}/{t.service}{half}" for half in ("Request", "Response")] if t.service else []
    if halves and all(h in edition for h in halves):  # an edition that lacks one half has no service MD5 here
        out["service_md5"] = service_md5(edition, *(edition[h] for h in halves))
    return out


def canonical(edition: Edition, message: dict) -> tuple[dict, bytes]:
    """The decoded form of ``message`` (values in their canonical form, e.g. the shortest fp32 decimal) and its bytes."""
    frame = codec.encode(edition, message)
    return codec.decode(edition, message["type"], frame), frame


def codec_cases(tc: TypeCases, edition: Edition, prefix: str, expect, examples: list[dict]) -> None:
    t, msg = tc.t, edition[tc.t.full]
    minimal = {"type": t.full, "fields": values.fields(edition, t.full, values.default)}
    filled = {"type": t.full, "fields": values.fields(edition, t.full, values.filled)}

    def valid(path, message, clause, tags, **extra):
        message, frame = canonical(edition, message)
        tc.add(prefix + path, expect=expect("valid"), clause=clause, checks=CODEC, tags=["valid", *tags],
               edition=edition, frame=frame, message=message, **extra)

    valid("minimal", minimal, t.clause, ["minimal", "defaults"])
    valid("filled", filled, t.clause, ["filled"])
    for example in examples:
        if canonical(edition, example["message"])[0] != example["message"]:
            raise ValueError(f"example {t.name}/{example['name']} is not in canonical form")
        valid(f"realistic/{example['name']}", example["message"], example["source"], ["realistic"])
    for f in msg.fields:
        for name, value, tags in values.variants(edition, f.type):
            compare = {"nan_payload": True} if values.pins_nan(tags) else None
            valid(f"field/{f.name}/{name}", with_field(minimal, f.name, value), t.clause,
                  [*tags, f"field:{f.name}", kind_tag(f.type)], compare=compare)
    add_invalid(tc, edition, prefix, expect, msg, filled)
    add_acceptable(tc, edition, prefix, expect, msg, filled)


def kind_tag(t: FieldType) -> str:
    if t.array is not None:
        return "kind:fixed-array" if t.array >= 0 else "kind:array"
    return f"kind:{t.base}" if t.is_builtin else "kind:message"


def with_field(message: dict, name: str, value) -> dict:
    out = copy.deepcopy(message)
    out["fields"][name] = value
    return out


def add_invalid(tc: TypeCases, edition: Edition, prefix: str, expect, msg: Message, filled: dict) -> None:
    full = msg.full
    canonical_filled, frame = canonical(edition, filled)
    spans = codec.layout(edition, full, frame)
    final_blob = final_blob_span(spans, len(frame))

    def invalid(path, broken: bytes, tags=(), at_final=False):
        try:
            codec.decode(edition, full, broken)
        except codec.FrameError as exc:
            rule = exc.rule
        else:
            raise ValueError(f"{full}: {path} decodes, but is meant to break a rule")
        found = flaws(edition, full, broken, rule)
        broke = {"rules": found, "why": WHY[path.split("/")[0]]} if len(found) > 1 else None
        tc.add(prefix + path, expect=expect("invalid"), clause=tc.clauses[rule], checks=DECODE, edition=edition,
               frame=broken, rule=rule, flaws=broke, base=f"ros_acomms/{tc.t.name}/{prefix}filled",
               tags=["invalid", f"rule:{rule}", *tags, *(["final-blob"] if at_final else [])])

    cuts = {0: "empty"}
    for s in spans:
        if s.end < len(frame):
            cuts.setdefault(s.end, f"after-{s.path}")
    for cut, name in sorted(cuts.items()):
        invalid(f"truncated/{name}", frame[:cut], at_final=final_blob is not None and cut >= final_blob.start)
    for s in spans:
        if s.role != "length":
            continue
        owner = s.path.removesuffix(".length")
        ftype = field_type_at(edition, msg, owner)
        element = 1 if ftype.array is None else codec.min_size(edition, ftype.element)  # the fewest bytes of one
        claim = (len(frame) - s.end) // element + 1
        at_final = final_blob is not None and s.end == final_blob.start
        invalid(f"length-overrun/{owner}", patch_u32(frame, s.start, claim), at_final=at_final)
        invalid(f"length-overrun/{owner}/huge", patch_u32(frame, s.start, 0xFFFFFFFF), ["class:huge-length"], at_final)
        if element > 1 and ftype.element.base in PRIMITIVES:
            # a length whose byte count (element size x length) is 2^32: 0 in a reader computing it in 32 bits
            invalid(f"length-overrun/{owner}/wraps", patch_u32(frame, s.start, 2 ** 32 // element),
                    ["class:wrapping-length"], at_final)
    add_encoder_choices(tc, edition, prefix, expect, msg, canonical_filled)


def add_encoder_choices(tc: TypeCases, edition: Edition, prefix: str, expect, msg: Message, filled: dict) -> None:
    """What an encoder is given that its type cannot carry: a fixed-length array of another length, an integer out of
    its type. Refusing is the reference's choice, not the documentation's: each is an implementation-defined class
    whose outcomes give the frames an encoder that writes something else may write."""
    for f in msg.fields:
        if f.type.array is not None and f.type.array >= 0:
            n = f.type.array
            element = values.filled(edition, f.type.element) if f.type.base != "uint8" else "a5"
            default = values.default(edition, f.type.element) if f.type.base != "uint8" else "00"
            for name, size in (("short", n - 1), ("long", n + 1)):
                given = [element] * size if f.type.base != "uint8" else element * size
                resized = (given[:n] if size > n else given + [default] * (n - size)) if f.type.base != "uint8" else (
                    given[:2 * n] if size > n else given + default * (n - size))
                tc.add(f"{prefix}fixed-array-length/{f.name}/{name}", expect=expect("acceptable"),
                       clause=tc.clauses["fixed-array-length"], checks=[f"encode-{ENC}"], edition=edition,
                       message=with_field(filled, f.name, given), reference=reference_of("fixed-array-length"),
                       outcomes=outcomes("fixed-array-length", resize=codec.encode(edition, with_field(filled, f.name, resized))),
                       tags=["acceptable", "fixed-array-length", f"field:{f.name}"], **{"class": "fixed-array-length"},
                       comment=f"{size} elements for {f.type.text('')}: refuse, or write exactly {n}; never {size}.")
        elif f.type.array is None and f.type.base in values.FILLED_INTS:
            lo, hi = codec.int_bounds(f.type.base)
            wrapped = lo if lo < 0 else 0  # hi + 1, its low-order bits in two's complement
            frames = {name: codec.encode(edition, with_field(filled, f.name, codec.int_form(value)))
                      for name, value in (("truncate", wrapped), ("saturate", hi))}
            tc.add(f"{prefix}value-out-of-type/{f.name}", expect=expect("acceptable"),
                   clause=tc.clauses["value-out-of-type"], checks=[f"encode-{ENC}"], edition=edition,
                   message=with_field(filled, f.name, codec.int_form(hi + 1)), reference=reference_of("value-out-of-type"),
                   outcomes=outcomes("value-out-of-type", **frames), **{"class": "value-out-of-type"},
                   tags=["acceptable", "value-out-of-type", f"field:{f.name}"],
                   comment=f"{hi + 1} in a {f.type.base}: refuse, write its low-order bits ({wrapped}), or {hi}.")


def final_blob_span(spans, length: int):
    """The data span of a string or uint8[] that ends the frame (a lenient reader slices it unchecked)."""
    last = max(spans, key=lambda s: (s.end, s.start))
    if last.end == length and last.role == "value" and last.type in ("string", "uint8[]"):
        return last
    return None


def field_type_at(edition: Edition, msg: Message, path: str) -> FieldType:
    """The type of the field a span path (``QueueStatus.queue_summaries[0].topic``) names."""
    ftype = FieldType(msg.full)
    for part in path.split(".")[1:]:
        name, _, index = part.partition("[")
        ftype = next(f.type for f in edition[ftype.base].fields if f.name == name)
        if index:
            ftype = ftype.element
    return ftype


def patch_u32(frame: bytes, offset: int, value: int) -> bytes:
    return frame[:offset] + struct.pack("<I", value) + frame[offset + 4:]


def add_acceptable(tc: TypeCases, edition: Edition, prefix: str, expect, msg: Message, filled: dict) -> None:
    canonical_filled, frame = canonical(edition, filled)
    receivers = SERIALIZATION

    def acceptable(path, klass, broken: bytes, message: dict, tags, **extra):
        extra.setdefault("outcomes", outcomes(klass))
        tc.add(prefix + path, expect=expect("acceptable"), clause=receivers, checks=DECODE, edition=edition,
               frame=broken, message=message, reference=reference_of(klass), tags=["acceptable", *tags],
               **{"class": klass}, **extra)

    acceptable("trailing-bytes", "trailing-bytes", frame + b"\x00\x11\x22", canonical_filled, ["trailing-bytes"],
               comment="Three bytes follow the message; genpy ignores them, rosbags refuses them.")
    spans = {s.path: s for s in codec.layout(edition, msg.full, frame)}
    for f in msg.fields:
        if f.type.array is not None or not f.type.is_builtin:
            continue
        span = spans[f"{msg.name}.{f.name}"]
        if f.type.base == "bool":
            acceptable(f"bool-byte/{f.name}", "bool-byte", frame[:span.start] + b"\x02" + frame[span.end:], canonical_filled,
                       ["bool", f"field:{f.name}"], comment="A bool byte that is neither 0 nor 1: read as true, or refused.")
        elif f.type.base == "string":
            message = with_field(canonical_filled, f.name, {"hex": "fffec3"})
            acceptable(f"non-utf8/{f.name}", "non-utf8", codec.encode(edition, message), message, ["string", f"field:{f.name}"],
                       comment="String bytes that are not UTF-8: ROS 1 strings are bytes, so keep them (as hex), refuse "
                               "them, or replace them (lossy).")
        elif f.type.base == "time":
            late = with_field(canonical_filled, f.name, {"secs": 1700000000, "nsecs": 1500000000})
            normal = with_field(canonical_filled, f.name, {"secs": 1700000001, "nsecs": 500000000})
            acceptable(f"time-nsecs-over/{f.name}", "time-nsecs-over", codec.encode(edition, late), late,
                       ["time", f"field:{f.name}"],
                       outcomes=[{"outcome": "accept"}, {"outcome": "normalize", "message": normal}, {"outcome": "reject"}],
                       comment="nsecs of a second and a half: keep it, carry it into secs (genpy's canon()), or refuse.")


# ---------------------------------------------------------------- files and coverage

def build_corpus(defs: RosDefinitions) -> dict[str, str]:
    """File name (relative to vectors/ros_acomms) -> exact text, for every generated file."""
    examples, rules = load_examples(), load_rules()
    clauses = {r["id"]: r["clause"] for r in rules}
    files, per_type = {}, {}
    groups = {t.name: t.full for t in defs.suite_types}
    promoted = promoted_cases(promote.read(ros_data("promoted.json"), "ros_acomms"), {
        e: RosFuzzSource(defs.edition(e), groups, clauses) for e in defs.editions})
    for t in defs.suite_types:
        cases = build_type(defs, t, examples.get(t.full, []), clauses) + promoted.get(t.name, [])
        per_type[t] = cases
        doc = {"$schema": "../../schema/ros_acomms-vectors.schema.json", "format": FORMAT_VERSION, "suite": "ros_acomms",
               "message": {"name": t.name, "type": t.full, "kind": t.kind, "clause": t.clause},
               "editions": [e for e in defs.editions if t.in_edition(e)], "cases": cases}
        files[f"cases/{t.name}.json"] = json.dumps(doc, indent=1, ensure_ascii=True) + "\n"
    files["coverage.md"] = coverage_markdown(defs, rules, per_type)
    files["provenance.md"] = provenance_markdown("ros_acomms", rules_document(), case_documents(files))
    statements = json.loads(ros_data("statements.json").read_text(encoding="utf-8"))["statements"]
    files["behaviour-coverage.md"] = behaviour_markdown("ros_acomms", statements, live_cases(ros_data()))
    return files


def rule_applies(rule: dict, defs: RosDefinitions, t: TypeDef) -> bool:
    scope = rule["applies_to"]
    if scope == "all":
        return True
    if scope == "encoder":
        return False
    kinds = set()
    for edition in (defs.edition(e) for e in defs.editions if t.in_edition(e)):
        for m in (edition[t.full], *edition.dependencies(edition[t.full])):
            for f in m.fields:
                kinds.add(kind_tag(f.type).split(":")[1])
                if f.type.base == "string":
                    kinds.add("string")
                if f.type.base in values.FILLED_INTS and f.type.array is None and m.full == t.full:
                    kinds.add("integer")
    return bool(kinds & set(scope))


def coverage_markdown(defs: RosDefinitions, rules: list[dict], per_type: dict[TypeDef, list[dict]]) -> str:
    problems = []
    lines = ["# ros_acomms corpus coverage", "", "Generated by `imc-conformance generate --suite ros_acomms` with the "
             "vectors; do not edit.", "", "## Cases per type and rule", "",
             "Invalid cases per rule; `n/a`: the rule cannot apply to the type. Types differing between editions have "
             "cases per edition.", ""]
    shown = [r for r in rules if r["level"] == "must"]
    head = ["type", "editions", "valid", "acceptable", "invalid", "definition"] + [r["id"] for r in shown]
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for t, cases in per_type.items():
        kinds = Counter(k for c in cases if "describe" not in c["checks"]
                        for k in ({c["expect"]} if isinstance(c["expect"], str) else set(c["expect"].values())))
        by_rule = Counter(c["rule"] for c in cases if "rule" in c)
        described = sum(1 for c in cases if "describe" in c["checks"])
        cells = [t.name, ", ".join(e for e in defs.editions if t.in_edition(e)), str(kinds["valid"]),
                 str(kinds["acceptable"]), str(kinds["invalid"]), str(described)]
        for r in shown:
            if rule_applies(r, defs, t):
                cells.append(str(by_rule[r["id"]]))
                if not by_rule[r["id"]]:
                    problems.append(f"{t.name}: no invalid case for rule {r['id']}")
            else:
                cells.append("n/a")
        if kinds["valid"] < MIN_VALID:
            problems.append(f"{t.name}: {kinds['valid']} valid cases, fewer than {MIN_VALID}")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "## Fields and value classes", "", "Valid (`v`) and acceptable (`a`) cases per field and value class.", ""]
    for t, cases in per_type.items():
        lines += [f"### {t.full} ({t.kind})", "", "| field | classes |", "|---|---|"]
        for f in t.fields:
            classes: dict[str, Counter] = defaultdict(Counter)
            for c in cases:
                if f"field:{f.name}" in c["tags"] and "invalid" not in c["tags"]:
                    cls = next((x.split(":", 1)[1] for x in c["tags"] if x.startswith("class:")), c["id"].rsplit("/", 2)[0].split("/")[-1])
                    for k in ({c["expect"]} if isinstance(c["expect"], str) else set(c["expect"].values())):
                        classes[cls][k[0]] += 1
            text = ", ".join(f"{cls} ({'/'.join(f'{n}{k}' for k, n in sorted(cnt.items()))})" for cls, cnt in classes.items())
            lines.append(f"| {f.name} ({f.type.text(t.package)}) | {text or 'defaults and filled only'} |")
        lines.append("")
    if problems:
        raise ValueError("coverage requirements not met:\n" + "\n".join(problems))
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="imc-conformance generate --suite ros_acomms", description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="report files that differ from a fresh build; write nothing")
    args = parser.parse_args(argv)
    defs = load_definitions()
    files = build_corpus(defs)
    if not proven(rules_document(), files, lambda documents: corpus_problems(defs, documents)):
        return 1  # a corpus the lint or the oracle refuses is not written
    return write_generated(load_suite("ros_acomms"), files, args.check, "vectors/ros_acomms")


if __name__ == "__main__":
    sys.exit(main())

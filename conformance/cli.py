"""``imc-conformance``: list the corpus, run it against an implementation, rebuild it."""

from __future__ import annotations

import argparse
import fnmatch
import importlib
import json
import sys
from collections import Counter
from pathlib import Path

from .corpus_data import implementation_errata, load_cases
from .definitions import load_definitions
from .evaluate import Judge, Verdict, expectation, plan, worst
from .library import ask

BUILTIN_ADAPTERS = {
    "imcpy": "imc_conformance.adapters.imcpy_adapter:adapter",
    "pyimclsts": "imc_conformance.adapters.pyimclsts_adapter:adapter",
}
DEFAULT_EDITION = "imc-5.4.30"
FAILING = {Verdict.FAIL, Verdict.CRASH, Verdict.TIMEOUT}


class UsageError(Exception):
    pass


def load_adapter(spec: str):
    """An adapter from a built-in name, ``module:attribute`` or ``path/to/file.py:attribute``."""
    spec = BUILTIN_ADAPTERS.get(spec, spec)
    target, _, attr = spec.rpartition(":")
    if not target or not attr:
        raise UsageError(f"adapter {spec!r}: expected a built-in name ({', '.join(BUILTIN_ADAPTERS)}) or module:attribute")
    try:
        if target.endswith(".py"):
            path = Path(target)
            loader = importlib.util.spec_from_file_location(path.stem, path)
            if loader is None or not path.exists():
                raise UsageError(f"adapter file {target} does not exist")
            module = importlib.util.module_from_spec(loader)
            loader.loader.exec_module(module)
        else:
            module = importlib.import_module(target)
        factory = getattr(module, attr)
    except UsageError:
        raise
    except Exception as exc:
        raise UsageError(f"cannot load adapter {spec!r}: {type(exc).__name__}: {exc}") from exc
    try:
        return factory() if callable(factory) and not hasattr(factory, "decode") else factory
    except Exception as exc:
        raise UsageError(f"adapter {spec!r} failed to start: {type(exc).__name__}: {exc}") from exc


def select(cases: list[dict], edition: str, messages: list[str], ids: list[str], tags: list[str]) -> list[dict]:
    out = []
    for case in cases:
        if expectation(case, edition) is None:
            continue
        if messages and case["id"].split("/")[1] not in messages:
            continue
        if ids and not any(fnmatch.fnmatchcase(case["id"], g) for g in ids):
            continue
        if tags and not set(tags) & set(case["tags"]):
            continue
        out.append(case)
    return out


def command_list(args) -> int:
    for case in select(load_cases(), args.edition, args.message, args.id, args.tag):
        print(f"{case['id']}\t{expectation(case, args.edition)}\t{case['clause']}")
    return 0


def command_run(args) -> int:
    from rich.console import Console
    from rich.table import Table

    defs = load_definitions()
    if args.message and (unknown := set(args.message) - set(defs.by_abbrev)):
        raise UsageError(f"unknown message(s): {', '.join(sorted(unknown))}")
    adapter = load_adapter(args.adapter)
    hello = adapter.hello()
    implementation, emits = str(hello.get("implementation", args.adapter)), set(hello.get("byte_orders", ()))
    cases = select(load_cases(), args.edition, args.message, args.id, args.tag)
    judge = Judge(defs)
    per_message: dict[str, Counter] = {}
    message_errata: dict[str, set] = {}
    rows = []
    for case in cases:
        results = [judge.judge(case, args.edition, r, ask(adapter, "imc", case, r)) for r in plan(case, args.edition, emits)]
        verdict = worst(results) if results else Verdict.UNSUPPORTED
        per_message.setdefault(case["id"].split("/")[1], Counter())[verdict] += 1
        errata = implementation_errata(case["id"], args.adapter) if verdict in FAILING else []
        message_errata.setdefault(case["id"].split("/")[1], set()).update(errata)
        rows.append({"id": case["id"], "verdict": verdict.value, "errata": errata,
                     "checks": [{"check": r.check, "verdict": r.verdict.value, "detail": r.detail, "outcome": r.outcome} for r in results]})
    console = Console(highlight=False)
    table = Table(title=f"{implementation} against the IMC corpus ({args.edition})")
    for col in ("message", "verdict", "PASS", "FAIL", "NON_STRICT", "IMPL_DEFINED", "other", "known errata"):
        table.add_column(col)
    failed_messages = 0
    for abbrev, counts in per_message.items():
        bad = sum(counts[v] for v in FAILING) or (args.strict and counts[Verdict.NON_STRICT])
        failed_messages += bool(bad)
        other = sum(n for v, n in counts.items() if v not in (Verdict.PASS, Verdict.FAIL, Verdict.NON_STRICT, Verdict.IMPL_DEFINED))
        table.add_row(abbrev, "[red]FAIL[/]" if bad else "[green]PASS[/]", str(counts[Verdict.PASS]), str(counts[Verdict.FAIL]),
                      str(counts[Verdict.NON_STRICT]), str(counts[Verdict.IMPL_DEFINED]), str(other),
                      ", ".join(sorted(message_errata[abbrev])))
    console.print(table)
    totals = Counter(r["verdict"] for r in rows)
    explained = sum(1 for r in rows if r["verdict"] == "FAIL" and r["errata"])
    console.print(f"{len(rows)} cases: " + ", ".join(f"{n} {v}" for v, n in sorted(totals.items()))
                  + (f" ({explained} failures are documented errata of {args.adapter})" if explained else ""))
    if args.json:
        Path(args.json).write_text(json.dumps({"suite": "imc", "edition": args.edition, "implementation": implementation,
                                               "summary": dict(totals), "cases": rows}, indent=1), encoding="utf-8")
    return 1 if failed_messages else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="imc-conformance", description="Conformance suite for IMC messages (LSTS).")
    sub = parser.add_subparsers(dest="command", required=True)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--edition", default=DEFAULT_EDITION, help=f"imc-5.4.11 (the seeds) or imc-5.4.30 (default: {DEFAULT_EDITION})")
    common.add_argument("--message", action="append", default=[], help="only this message (repeatable), e.g. LblRange")
    common.add_argument("--id", action="append", default=[], help="only case ids matching this glob (repeatable)")
    common.add_argument("--tag", action="append", default=[], help="only cases with this tag (repeatable)")
    sub.add_parser("list", parents=[common], help="list the selected cases").set_defaults(func=command_list)
    run = sub.add_parser("run", parents=[common], help="run the corpus against an implementation")
    run.add_argument("--adapter", default="imcpy", help="imcpy (default), pyimclsts, module:attribute or file.py:attribute")
    run.add_argument("--strict", action="store_true", help="NON_STRICT verdicts fail too")
    run.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    run.set_defaults(func=command_run)
    gen = sub.add_parser("generate", help="rebuild vectors/imc/cases and the coverage table from the definitions")
    gen.add_argument("--check", action="store_true", help="only report drift")
    gen.set_defaults(func=lambda a: __import__("imc_conformance.corpus.build", fromlist=["main"]).main(["--check"] if a.check else []))
    args = parser.parse_args(argv)
    if args.edition not in ("imc-5.4.11", "imc-5.4.30") if hasattr(args, "edition") else False:
        parser.error(f"unknown edition {args.edition!r}")
    try:
        return args.func(args)
    except UsageError as exc:
        print(f"imc-conformance: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into head(1) and the like
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())

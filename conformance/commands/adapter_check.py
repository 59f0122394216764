"""``imc-conformance adapter-check``: does an adapter speak the adapter contract (adapters/README.md, installed with
the package)? A short, fixed set of requests (the hello, an unknown operation, requests in flight together, a batch, the suite's probes), each mistake
explained in plain words with its fix. Exit 0 only when there is none; what a newcomer runs first."""

from __future__ import annotations

from .options import add_adapter, add_suite

SHOWN = 3  # examples shown of each kind of mistake


def add(sub) -> None:
    check = sub.add_parser("adapter-check", help="check that an adapter speaks the adapter contract: each mistake "
                                                 "explained with its fix")
    add_adapter(check, what="the adapter to check")
    add_suite(check)
    check.add_argument("--edition", help="the edition whose probes to send (default: the suite's first)")
    check.add_argument("--message", metavar="MESSAGE", action="append", default=[],
                       help="check only this message (repeatable): its first pass and probes")
    check.set_defaults(func=command)


def command(args) -> int:
    from ..core.session import AdapterStartError
    from ..escaping import printable
    from ..files import open_corpus
    from ..adaptercheck.check import check
    from ..adaptercheck.mistakes import Mistake, fix_in, language
    from ..paths import CONTRACT
    from .adapters import adapter_choice, open_session
    from ..arguments import chosen_edition, known_groups
    from ..core.wording import counted

    suite, cases = open_corpus(args.suite)
    edition = chosen_edition(suite, args.edition)
    if args.message:
        known_groups(suite, args.message, [g.name for g in suite.groups])
        cases = [c for c in cases if c.group in args.message]
    name, argv = adapter_choice(args, suite)
    session = open_session(name, argv, args, suite)
    try:
        outcome = check(session, suite, cases, edition, args.timeout)
    except AdapterStartError as exc:  # a library adapter whose hello raised
        from ..adaptercheck.check import Outcome

        outcome = Outcome(mistakes=[Mistake("hello-fields", str(exc), "hello")])
    finally:
        session.close()
    print(f"adapter-check of {printable(name)} ({suite.name}, edition {edition})"
          + (f": {printable(outcome.implementation)}" if outcome.implementation else ""))
    for line in outcome.passed:
        print(f"  ok    {printable(line)}")
    for finding in outcome.findings:
        print(f"  note  {printable(finding)[:400]} (the implementation's own result: a run judges it)")
    if outcome.either:
        either(outcome)
    if outcome.rules:
        rule_readings(outcome)
    if outcome.nothing:
        print("  note  every probe was answered \"unsupported\": the adapter speaks the contract but implements "
              "nothing yet (put the implementation's calls where the starter says TODO); a run of it tests nothing "
              "and exits 2")
    kinds = outcome.by_kind()
    for n, same in enumerate(kinds, 1):
        print(f"MISTAKE {n}: {same[0].what}" + (f" ({len(same)} times)" if len(same) > 1 else ""))
        for mistake in same[:SHOWN]:
            print(f"  seen: {printable(mistake.seen)[:400]}" + (f" [{printable(mistake.where)}]" if mistake.where else ""))
        if len(same) > SHOWN:
            print(f"  … and {len(same) - SHOWN} more like these")
        print(f"  fix:  {fix_in(same[0].code, language(argv))}")
    if kinds:
        print(f"{counted(len(kinds), 'kind')} of mistake: the adapter does not speak the contract "
              f"yet (the contract: {CONTRACT})")
        return 1
    print(f"the adapter speaks the contract ({CONTRACT}); next: imc-conformance run with the same options")
    return 0


def _notes(lines: list[str]) -> None:
    """The first SHOWN notes, and how many more there are."""
    from ..escaping import printable

    for line in lines[:SHOWN]:
        print(f"  note  {printable(line)[:400]}")
    if len(lines) > SHOWN:
        print(f"        … and {len(lines) - SHOWN} more like these")


def either(outcome) -> None:
    """Encode probes whose frame holds another value than the request gave: both readings, and how to tell them."""
    _notes(outcome.either)
    print("        either the implementation writes these values so (e.g. it canonicalises a NaN's bits when it writes "
          "a float): its own result, which a run judges (a FAIL of those encode checks, not the adapter's)")
    print("        or the adapter changed the value before handing it over (a \"nan:<hex>\" read as a plain NaN, an "
          "fp32 read as a double, -0.0 read as 0): its mistake")
    decoded = ("the adapter decoded the same probes right, so it writes these values right; " if outcome.decoded_right
               else "")
    print(f"        to tell: {decoded}log the value the adapter hands the implementation (on stderr), or check its "
          "value parser alone (the starters' --values reads value probes and answers them without the "
          "implementation): if the value is right when handed over, the frame is the implementation's")


def rule_readings(outcome) -> None:
    """Refusals naming a rule the input does not break, each for one kind of input: both readings, and how to tell."""
    _notes(outcome.rules)
    print("        either the implementation's own check refused it under that rule (e.g. its transport takes the CRC "
          "from the datagram's last two bytes, not from the frame's footer): its own result, which a run judges "
          "NON_STRICT (the adapter reports it faithfully: keep naming the rule)")
    print("        or the adapter names a rule the implementation did not give: its mistake")
    print("        to tell: read the implementation's own error for this input (the answer's \"error\" above): if it is "
          "that rule's check that failed, the result is the implementation's; the adapter names that rule for no "
          "other kind of input, which an adapter naming one rule for every refusal would")

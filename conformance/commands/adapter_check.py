"""``imc-conformance adapter-check``: does an adapter speak the contract of adapters/README.md? A short, fixed set of
requests (the hello, an unknown operation, requests in flight together, a batch, the suite's probes), each mistake
explained in plain words with its fix. Exit 0 only when there is none; what a newcomer runs first."""

from __future__ import annotations

from .options import add_adapter, add_suite

SHOWN = 3  # examples shown of each kind of mistake


def add(sub) -> None:
    check = sub.add_parser("adapter-check", help="check that an adapter speaks the contract (adapters/README.md): "
                                                 "each mistake explained with its fix")
    add_adapter(check, what="the adapter to check")
    add_suite(check)
    check.add_argument("--edition", help="the edition whose probes to send (default: the suite's first)")
    check.set_defaults(func=command)


def command(args) -> int:
    from ..core.session import AdapterStartError
    from ..escaping import printable
    from ..files import open_corpus
    from ..adaptercheck.check import check
    from ..adaptercheck.mistakes import README, Mistake
    from .adapters import adapter_choice, open_session
    from ..arguments import chosen_edition

    suite, cases = open_corpus(args.suite)
    edition = chosen_edition(suite, args.edition)
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
    kinds = outcome.by_kind()
    for n, same in enumerate(kinds, 1):
        print(f"MISTAKE {n}: {same[0].what}" + (f" ({len(same)} times)" if len(same) > 1 else ""))
        for mistake in same[:SHOWN]:
            print(f"  seen: {printable(mistake.seen)[:400]}" + (f" [{printable(mistake.where)}]" if mistake.where else ""))
        if len(same) > SHOWN:
            print(f"  … and {len(same) - SHOWN} more like these")
        print(f"  fix:  {same[0].fix}")
    if kinds:
        print(f"{len(kinds)} kind{'s' if len(kinds) != 1 else ''} of mistake: the adapter does not speak the contract "
              f"yet ({README})")
        return 1
    print(f"the adapter speaks the contract ({README}); next: imc-conformance run with the same options")
    return 0

"""What ``run`` needs for live cases (scenarios and the robustness phase), whatever the suite: the run's options
checked against the suite's vocabulary, the notes a report gives on them, ``--dry-run``, ``list --scenarios``,
and opening a ``--target`` with an optional ``--restart-cmd`` (``restart.py``)."""

from __future__ import annotations

import json
from pathlib import Path

from .kinds.scenario import options as vocabulary
from .escaping import printable

LIVE_FLAGS = ("target", "param", "allow_effects", "claims", "profile", "robustness", "restart_cmd", "replay_effects",
              "dry_run")


def options(args, suite, everything) -> dict:
    """The run's settings the live case kinds read; {} for a suite without live cases (a ValueError if live
    options were given to it anyway)."""
    behaviour = suite.behaviour
    if behaviour is None:
        given = [f"--{f.replace('_', '-')}" for f in LIVE_FLAGS if getattr(args, f)] + (
            ["--time-scale"] if args.time_scale != 1.0 else [])
        if given:
            raise ValueError(f"the suite {suite.name!r} has no live cases: {', '.join(given)} do not apply")
        return {}
    if args.robustness and "robustness" not in suite.kinds:
        raise ValueError(f"--robustness: the suite {suite.name!r} has no robustness phase")
    for flag, given in (("--robustness", args.robustness), ("--restart-cmd", args.restart_cmd is not None),
                        ("--replay-effects", args.replay_effects)):
        if given and not args.target:
            raise ValueError(f"{flag} is for a live target: give --target udp://HOST:PORT")
    if (args.restart_cmd is not None or args.replay_effects) and not args.robustness:
        raise ValueError("--restart-cmd and --replay-effects are for the robustness phase: give --robustness too")
    out = {"params": vocabulary.parameters(behaviour, args.param),
           "effects": vocabulary.effects(behaviour, args.allow_effects),
           "time_scale": args.time_scale, "profile": suite.profile(args.profile or "seed"),
           "robustness": args.robustness, "restart": bool(args.restart_cmd), "replay_effects": args.replay_effects,
           "corpus": tuple(c for c in everything if c.kind == "vector")}
    if args.restart_cmd is not None:
        from .restart import restart_argv

        restart_argv(args.restart_cmd)  # its program found before the run, not at the first bisection
    check_params(suite, everything, out["params"])
    if args.claims:
        from .inputs import read_json
        try:
            _, doc = read_json(Path(args.claims), unique=True)
        except ValueError as exc:
            raise ValueError(f"--claims: {exc}") from None
        try:
            out["claims"] = vocabulary.claims(behaviour, doc)
        except ValueError as exc:
            raise ValueError(f"--claims {args.claims}: {exc}") from None
    return out


def check_params(suite, everything, params: dict) -> None:
    """A usage error for a parameter that a live case's message cannot carry (a number too large for its field,
    a name too long for a datagram), before anything is sent."""
    if not params:
        return
    for case in everything:
        if case.kind in ("scenario", "robustness") and set(case.data.get("needs", ())) & set(params):
            problem = suite.live_problem(case.kind, case.data, params)
            if problem:
                given = ", ".join(f"{n}={params[n]}"[:60] for n in case.data["needs"] if n in params)
                raise ValueError(f"--param {given}: {case.id}{problem[0]}: {problem[1]}"[:400])


def notes(args, options: dict) -> list[str]:
    """What the report says the live cases ran under (a run against a live target)."""
    if not options or not args.target:
        return []
    out = [f"profile: {options['profile']['name']}"]
    if "claims" in options:
        out.append(f"claims ({args.claims}): {claimed(options['claims'])}")
    if options["params"]:
        out.append("parameters: " + ", ".join(f"{k}={v}" for k, v in options["params"].items()))
    if options["effects"]:
        out.append(f"effects allowed: {', '.join(sorted(options['effects']))}")
    if options["time_scale"] != 1.0:
        out.append(f"time bounds scaled by {options['time_scale']:g}")
    return out


def claimed(claims: dict) -> str:
    """What a run's claims say, for a report's notes."""
    return ", ".join(f"{name}{' (only to itself)' if scope == 'self' else ''}" for name, scope in sorted(claims.items())) \
        or "nothing"


def dry_run(suite, cases, args, options) -> int:
    """Print what each selected live case would send, and send nothing."""
    from .kinds.scenario import Addressing
    from .kinds.scenario.dryrun import planned_sends

    addressing = Addressing(args.src, 0, args.dst)
    for case in cases:
        kind = suite.kinds[case.kind]
        if not hasattr(kind, "admit"):
            continue
        why = kind.admit(case.data, options)
        plans = [] if why else kind.plan(case.data, args.edition, set(suite.encodings), options)
        if why or not plans or plans[0].op == "skip":
            reason = f"not run ({why})" if why else plans[0].params["reason"] if plans else "not in this edition"
            print(f"{case.id}: {reason}")
            continue
        program = plans[0].params["program"]
        phase = getattr(program, "phase", None)
        if phase is not None:
            print(f"{case.id}: the robustness phase: {len(phase.frames)} corpus frames in blocks of "
                  f"{phase.settings['block']}, then {phase.settings['garbage']} garbage datagrams; this probe, before, "
                  "after each block and after the garbage:")
        sends = planned_sends(program, addressing, 0.0)
        if not sends:
            waits = [f"{k} {s[k]}" for s in program.scenario["steps"] for k in ("alive", "expect") if k in s]
            print(f"{case.id}: sends nothing; waits for: {', '.join(waits)}")
        for step, sent in sends:
            text = sent if isinstance(sent, str) else json.dumps({k: v for k, v in sent.items() if k != "header"})
            print(f"{case.id} {step}: {printable(text)}")
    return 0


def list_live_cases(suite, cases) -> int:
    """``list --scenarios``: the live cases with what they need, do and exercise, then the vocabulary."""
    behaviour = suite.behaviour
    if behaviour is None:
        raise ValueError(f"the suite {suite.name!r} has no live cases")
    for case in (c for c in cases if hasattr(suite.kinds[c.kind], "admit")):
        d = case.data
        print(f"{case.id}\tneeds: {','.join(d.get('needs', ())) or '-'}\teffects: {','.join(d.get('effects', ())) or '-'}"
              f"\tcapability: {d.get('capability', '-')}\t{d['clause']}")
    print("# parameters (--param NAME=VALUE):")
    for name, p in behaviour["params"].items():
        print(f"#   {name}: {p['description']} ({p['type']}, e.g. {p['example']})")
    print(f"# effects (--allow-effects all or a list): {', '.join(behaviour['effects'])}")
    print("# capabilities (--claims FILE: services claim all of theirs; capabilities: any, self or none):")
    for name, c in behaviour["capabilities"].items():
        print(f"#   {name} (service {c['service']}): {c['description']}")
    return 0


def first_unique() -> int:
    """Where a run's request ids start: random, so that two runs on one node (or one after the other) do not answer
    to each other's numbers; recorded with the run, so that a replay finds the same."""
    import secrets

    from .limits import UNIQUE_SPAN

    return secrets.randbelow(UNIQUE_SPAN)


def open_target(args, suite, recorder=None):
    """The session with ``--target`` (its datagrams told to ``recorder``); ValueError with a one-line reason."""
    restart = None
    if args.restart_cmd is not None:
        from .restart import restart_argv, restarter

        restart = restarter(restart_argv(args.restart_cmd))
    return suite.open_target(args.target, bind=args.bind, src=args.src, dst=args.dst,
                             allow_group=args.allow_multicast, startup=args.startup, restart=restart,
                             recorder=recorder, first_unique=args.first_unique)

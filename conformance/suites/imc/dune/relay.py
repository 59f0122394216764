"""``make dune-relay``: DUNE against DUNE through the relay, inside a private network namespace it creates (as
``make dune-conformance`` does): DUNE's lauv-simulator-1 configuration as two systems of their own, lauv-xplore-3 the
vehicle and lauv-xplore-2 the console (their state and logs apart from the other DUNE scripts' systems, so both can run
at once). Neither announces itself (an Announce on loopback would tell each the other's own
address, and their traffic would bypass the relay): each sends its UDP transport's messages to a static destination,
the relay's socket facing it, and takes what comes without the contact filter (``Ignore Filter``); each sends only its
own system's messages (``Local Messages Only``: else each would send the other's back, and they would circle). The relay judges
both sides with the whole protocol (``--suite imc-full``: DUNE's traffic is mostly messages outside the suite's) over a
clean link, then over an impaired one; ``reports/dune-relay-<link>.{json,html,pcapng}``. Never in CI.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import time
from pathlib import Path

from .build import home, source
from .conformance import entered
from .world import CONFIG_DIR, MODEM, SHARED, UDP_MESSAGES, dune_argv, forget_state, start, stop

VEHICLE, CONSOLE = "lauv-xplore-3", "lauv-xplore-2"
VEHICLE_ID = "0x0020"  # lauv-xplore-3 in DUNE's etc/common/imc-addresses.ini
VEHICLE_PORT, CONSOLE_PORT, LISTEN, VIA = 6002, 6003, 6010, 6011
STARTUP = 5.0  # seconds DUNE takes to start its transports before the relay listens

NOT_ANNOUNCED = """
[Transports.Announce]
Enabled = Never

[Transports.Discovery]
Enabled = Never
"""

VEHICLE_INI = """\
# Written by imc-conformance (make dune-relay): DUNE's lauv-simulator-1 configuration as the vehicle, its UDP transport
# sending only to the relay, announcing nothing.
[Require ../lauv-simulator-1.ini]
{shared}
[General]
Vehicle = {name}
{quiet}
[Transports.UDP]
Local Port = {port}
Static Destinations = 127.0.0.1:{to}
Ignore Filter = true
Local Messages Only = true
{transports}
{modem}
[Simulators.Iridium]
Enabled = Never

[Transports.DataStore]
Enabled = Always
Entity Label = DataStore Transport
"""

CONSOLE_INI = """\
# Written by imc-conformance (make dune-relay): lauv-xplore-2 as the console, its UDP transport sending only to the
# relay, announcing nothing, with no other IP transport (its ports would collide with the vehicle's).
[Require ../lauv-simulator-1.ini]

[General]
Vehicle = {name}

[Simulators.GPS]
Initial Position = 41.1859, -8.7062
{quiet}{disabled}
[Transports.UDP]
Local Port = {port}
Static Destinations = 127.0.0.1:{to}
Ignore Filter = true
Local Messages Only = true

[Simulators.Iridium]
Enabled = Never
"""

CONSOLE_WITHOUT = ("Transports.HTTP", "Transports.FTP", "Transports.TCP.Server/SlaveCPU", "Transports.TCP.Server/BackSeat",
                   "Transports.TCPOnDemand")


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="make dune-relay", description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="how long each link is relayed (default 60)")
    parser.add_argument("--impair", default="loss=0.3,delay=2", help="the impaired link (default loss=0.3,delay=2)")
    parser.add_argument("--seed", type=int, default=1, help="the impairment's seed (default 1)")
    parser.add_argument("--reports", type=Path, default=Path("reports"), help="where to write the reports")
    parser.add_argument("--console", choices=("dune", "session", "imcpy", "both", "all"), default="all",
                        help="the console: a second DUNE, the suite's own session (its HistoricDataQuery scenarios), "
                             "an imcpy actor (imcpy_console.py), the first two in turn (both), or all three (default)")
    args = parser.parse_args(argv)
    done = entered(argv, "relay", "make dune-relay")
    if done is not None:
        return done
    args.reports.mkdir(parents=True, exist_ok=True)
    codes = {}
    try:
        for console in {"both": ("dune", "session"), "all": ("dune", "session", "imcpy")}.get(args.console,
                                                                                              (args.console,)):
            for name, spec in (("clean", ""), ("impaired", args.impair)):
                name = name if console == "dune" else f"{console}-{name}"
                codes[name] = _pair(args, name, spec, console)
    except KeyboardInterrupt:
        print("make dune-relay: interrupted", file=sys.stderr)
        return 130
    for name in codes:
        result = json.loads((args.reports / f"dune-relay-{name}.json").read_text())
        counts: dict[str, int] = {}
        for message in result["messages"]:
            for case in message["cases"]:
                counts[case["verdict"]] = counts.get(case["verdict"], 0) + 1
        print(f"dune-relay {name}: exit {codes[name]}; " + ", ".join(f"{n} {v}" for v, n in sorted(counts.items())))
    return 0 if all(code in (0, 1) for code in codes.values()) else 2


def _pair(args, name: str, spec: str, console: str = "dune") -> int:
    """The DUNEs started afresh, relayed for ``--seconds`` over the link ``spec``, stopped; the relay's exit code.
    ``console``: a second DUNE, the suite's own session (the HistoricDataQuery scenarios, which DUNE's DataStore
    answers) or an imcpy actor (``imcpy_console.py``); with the last two, the vehicle sends the replies they wait
    for."""
    import subprocess

    from ....cli import main as cli

    run = home() / "run-relay"
    run.mkdir(parents=True, exist_ok=True)
    folder = source() / "etc" / CONFIG_DIR
    folder.mkdir(parents=True, exist_ok=True)
    disabled = "".join(f"\n[{task}]\nEnabled = Never\n" for task in CONSOLE_WITHOUT)
    session = console != "dune"
    transports = f"Transports = {', '.join(UDP_MESSAGES)}" if session else ""
    acoustic = console == "imcpy"  # the acoustic modem simulator, so that AcousticSystemsQuery is served too
    if acoustic:
        (folder / "shared.ini").write_text(SHARED)
    (folder / "relay-vehicle.ini").write_text(VEHICLE_INI.format(name=VEHICLE, quiet=NOT_ANNOUNCED, port=VEHICLE_PORT,
                                                                 to=VIA, transports=transports,
                                                                 shared="[Require shared.ini]\n" if acoustic else "",
                                                                 modem=MODEM.format(seed=1) if acoustic else ""))
    (folder / "relay-console.ini").write_text(CONSOLE_INI.format(name=CONSOLE, quiet=NOT_ANNOUNCED, disabled=disabled,
                                                                 port=CONSOLE_PORT, to=LISTEN))
    processes = ("vehicle",) if session else ("vehicle", "console")
    for system in (VEHICLE, CONSOLE):
        forget_state(system)
    for process in processes:
        start(run, process, dune_argv(f"relay-{process}"))
    out = args.reports / f"dune-relay-{name}"
    relay = ["relay", f"udp://127.0.0.1:{LISTEN}", "--vehicle", f"udp://127.0.0.1:{VEHICLE_PORT}", "--via",
             f"127.0.0.1:{VIA}", "--impair", spec, "--seed", str(args.seed), "--pcap", f"{out}.pcapng", "--json",
             f"{out}.json", "--html", f"{out}.html", "--suite", "imc-full"]
    try:
        time.sleep(STARTUP)
        if not session:
            return cli([*relay, "--duration", str(args.seconds)])
        relaying = subprocess.Popen([str(Path(sys.executable).parent / "imc-conformance"), *relay, "--duration", "1800"])
        try:
            time.sleep(2.0)
            if console == "imcpy":
                subprocess.run([sys.executable, "-m", "imc_conformance.suites.imc.dune.imcpy_console", "--relay",
                                str(LISTEN), "--vehicle", VEHICLE_ID, "--name", VEHICLE, "--seconds", str(args.seconds),
                                "--json", f"{out}-console.json"], timeout=args.seconds + 60)
            else:
                cli(["run", "--no-progress", "--target", f"udp://127.0.0.1:{LISTEN}", "--startup", "40", "--message",
                     "HistoricDataQuery", "--json", f"{out}-console.json"])
        finally:
            relaying.send_signal(signal.SIGTERM)
            code = relaying.wait(120)
        return code
    finally:
        for process in processes:
            stop(run, process)

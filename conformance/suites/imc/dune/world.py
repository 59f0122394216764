"""The world a DUNE run needs, inside a private network namespace: DUNE as the vehicle under test, a second DUNE
as its acoustic peer over the simulated acoustic modem, and a local HTTP server standing in for the Iridium
gateway. The configuration files are written by this module (DUNE's own lauv-simulator-1 configuration, required
from them, stays as DUNE ships it), and every process is started in a session of its own and stopped by its PID.

Process bookkeeping lives in a run folder (a PID file and the command of each process) so that a separate
process, the ``--restart-cmd`` the robustness phase calls, can restart the vehicle and its peer.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import threading
import time
from pathlib import Path

from ..node.gateway import GatewayServer
from .build import binary, source

VEHICLE, VEHICLE_ID = "lauv-simulator-1", 0x00D1
PEER, PEER_ID = "lauv-xplore-1", 0x001E
UDP_PORT, IRIDIUM_PORT = 6002, 8888
GATEWAY_GONE = 10.0  # seconds the stand-in stays away once a message asks it to vanish
CONFIG_DIR = "imc-conformance"  # under DUNE's etc/, in the cache's copy of the sdist

# What DUNE's UDP transport sends to its peers: the replies the scenarios wait for (a plain "Transports =" replaces
# the list lauv-simulator-1 builds, which names the Iridium messages twice and much else no scenario reads).
UDP_MESSAGES = ("Heartbeat", "EntityList", "AcousticSystems", "AcousticOperation", "AcousticStatus", "LblConfig",
                "HistoricDataQuery", "HistoricData", "IridiumTxStatus", "SmsState", "RemoteCommand")

SHARED = """\
# Written by imc-conformance (conformance/suites/imc/dune/world.py): the acoustic address book both systems share.
# Transports.UAN lists it in AcousticSystems; Transports.CommManager routes with it; the modem simulator matches
# system names directly, and both names are in DUNE's own [IMC Addresses].
[Conformance Acoustic Addresses]
lauv-simulator-1 = 1
lauv-xplore-1 = 2
broadcast = 14
"""

MODEM = """
[Transports.UAN]
Enabled = Always
Entity Label = Acoustic Access Controller
Address Section = Conformance Acoustic Addresses

[Transports.CommManager]
Acoustic Address Section = Conformance Acoustic Addresses

[Simulators.AcousticModem]
Enabled = Simulation
Entity Label = Acoustic Modem Simulator
Modem Type = Evologics
Transmission Speed = 4000
# Delivery probability falls with distance over this deviation: 1000 km makes delivery at 100 m certain.
Distance Standard Deviation = 1000000
PRNG Seed = {seed}
"""

VEHICLE_INI = """\
# Written by imc-conformance: DUNE's lauv-simulator-1 as the node under test, on UDP {port}, announcing on
# loopback only, with the acoustic modem simulator, the Iridium simulator and the data store.
[Require ../lauv-simulator-1.ini]
[Require shared.ini]

[Transports.Announce]
Enable Loopback = true
Enable Multicast = false
Enable Broadcast = false

[Transports.UDP]
Local Port = {port}
{transports}
{modem}
[Simulators.Iridium]
Enabled = Simulation
Entity Label = Iridium Modem
Server Address = 127.0.0.1
Server Port = {iridium}

[Transports.DataStore]
Enabled = Always
Entity Label = DataStore Transport
"""

PEER_INI = """\
# Written by imc-conformance: lauv-xplore-1 as the vehicle's acoustic peer, about 100 m north of it, with no IP
# transport (its ports would collide with the vehicle's in the namespace).
[Require ../lauv-simulator-1.ini]
[Require shared.ini]

[General]
Vehicle = lauv-xplore-1

[Simulators.GPS]
Initial Position = 41.1859, -8.7062
{disabled}{modem}"""

PEER_WITHOUT = ("Transports.UDP", "Transports.Announce", "Transports.Discovery", "Transports.HTTP", "Transports.FTP",
                "Transports.TCP.Server/SlaveCPU", "Transports.TCP.Server/BackSeat", "Transports.TCPOnDemand")


def write_configs(record_to: int | None = None) -> Path:
    """Write the configuration files into DUNE's etc/ (of the cache's sdist copy); the folder. ``record_to``: a
    loopback port the vehicle sends DUNE's own list of transported messages to (for a recording of its whole traffic)
    instead of the scenarios' replies."""
    folder = source() / "etc" / CONFIG_DIR
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "shared.ini").write_text(SHARED)
    transports = (f"Transports = {', '.join(UDP_MESSAGES)}" if record_to is None
                  else f"Static Destinations = 127.0.0.1:{record_to}")
    (folder / "vehicle.ini").write_text(VEHICLE_INI.format(port=UDP_PORT, transports=transports,
                                                           modem=MODEM.format(seed=1), iridium=IRIDIUM_PORT))
    disabled = "".join(f"\n[{task}]\nEnabled = Never\n" for task in PEER_WITHOUT)
    (folder / "peer.ini").write_text(PEER_INI.format(disabled=disabled, modem=MODEM.format(seed=2)))
    return folder


def dune_argv(config: str) -> list[str]:
    return [str(binary()), "-d", str(source() / "etc"), "-c", f"{CONFIG_DIR}/{config}", "-p", "Simulation"]


def forget_state(system: str) -> None:
    """Remove what a DUNE system keeps between runs (its cache replays the last LblConfig at start-up)."""
    shutil.rmtree(binary().parent / "db" / system, ignore_errors=True)


# ---------------------------------------------------------------- processes, by PID files in the run folder

def start(run: Path, name: str, argv: list[str]) -> int:
    """Start a process in a session of its own, its output in ``<run>/<name>.log``; its PID."""
    log = (run / f"{name}.log").open("ab")
    proc = subprocess.Popen(argv, cwd=binary().parent, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True)
    log.close()
    (run / f"{name}.pid").write_text(str(proc.pid))
    (run / f"{name}.json").write_text(json.dumps(argv))
    return proc.pid


def stop(run: Path, name: str, grace: float = 10.0) -> None:
    """Stop a process started by ``start`` (its whole session): SIGTERM, then SIGKILL after ``grace`` seconds."""
    pid_file = run / f"{name}.pid"
    if not pid_file.exists():
        return
    pid = int(pid_file.read_text())
    for sig, wait in ((signal.SIGTERM, grace), (signal.SIGKILL, 5.0)):
        try:
            os.killpg(pid, sig)
        except ProcessLookupError:
            break
        end = time.monotonic() + wait
        while alive(pid) and time.monotonic() < end:
            _reap(pid)
            time.sleep(0.1)
        if not alive(pid):
            break
    pid_file.unlink(missing_ok=True)


def restart(run: Path, name: str, system: str) -> None:
    """Stop a process, forget its system's state, start it again with the same command."""
    argv = json.loads((run / f"{name}.json").read_text())
    stop(run, name)
    forget_state(system)
    start(run, name, argv)


def alive(pid: int) -> bool:
    """Whether a process runs (a zombie does not)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _reap(pid: int) -> None:
    try:
        os.waitpid(pid, os.WNOHANG)
    except ChildProcessError:
        pass  # not our child (a restart started it): init reaps it


def leftovers() -> list[int]:
    """PIDs of DUNE processes of the cached binary still running."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if os.readlink(entry / "exe") == str(binary()) and alive(int(entry.name)):
                    out.append(int(entry.name))
            except OSError:
                continue
    return out


# ---------------------------------------------------------------- the Iridium gateway stand-in

def iridium_gateway() -> GatewayServer:
    """The gateway stand-in (node/gateway.py) on 127.0.0.1, where DUNE's Simulators.Iridium posts: it takes every
    upload, but those whose data asks it to fail, answer late or vanish (it must run inside the namespace)."""
    server = GatewayServer(("127.0.0.1", IRIDIUM_PORT), gone=GATEWAY_GONE)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server

"""Run inside a network namespace the test creates (unshare): watch --iface lo while two sockets exchange IMC
frames on it, then stop it with SIGINT once it has judged them (its progress lines say so)."""
import signal, socket, subprocess, sys, time
from imc_conformance.suites import load_suite
from imc_conformance.suites.imc import codec

out = sys.argv[1]
subprocess.run(["ip", "link", "set", "lo", "up"], check=True)
defs = load_suite("imc").defs
def frame(abbrev, fields, src, dst):
    return codec.encode(defs, {"abbrev": abbrev, "header": {"timestamp": 1.0, "src": src, "src_ent": 1, "dst": dst,
                                                           "dst_ent": 255}, "fields": fields})
watch = subprocess.Popen([sys.executable, "-m", "imc_conformance.cli", "watch", "--iface", "lo", "--json", out],
                         stderr=subprocess.PIPE, text=True)
print(watch.stderr.readline().strip(), file=sys.stderr)
a, b = socket.socket(socket.AF_INET, socket.SOCK_DGRAM), socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
a.bind(("127.0.0.1", 6001)); b.bind(("127.0.0.1", 6002))
a.sendto(frame("AcousticSystemsQuery", {}, 0x4CF0, 30), ("127.0.0.1", 6002))
b.sendto(frame("AcousticSystems", {"list": "p1"}, 30, 0x4CF0), ("127.0.0.1", 6001))
a.sendto(b"\x54\xfe garbage", ("127.0.0.1", 6002))
bound = time.monotonic() + 60
for line in watch.stderr:
    if " records" in line and int(line.split()[1].replace(",", "")) >= 3 or time.monotonic() > bound:
        break
watch.send_signal(signal.SIGINT)
watch.communicate(timeout=60)
sys.exit(watch.returncode)

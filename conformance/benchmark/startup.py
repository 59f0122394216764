"""Start-up: whole processes of the package as a user installs it (the wheel in a virtual environment outside the
checkout, ``measure.install_wheel``), each beside the bare interpreter doing the least the command must: ``--version``
and ``list`` beside ``python -c pass``, a run of one message with imcpy beside ``python -c "import imcpy"``."""

from __future__ import annotations

import tempfile

from .measure import bare, command_env, median_of, whole


def startup_rows(repeat: int) -> dict[str, float]:
    env = command_env()
    whole(["--version"], env)  # bytecode written once, as an installed package has it
    out = {"version": median_of(repeat, lambda: whole(["--version"], env)),
           "list": median_of(repeat, lambda: whole(["list"], env)),
           "one message": median_of(repeat, lambda: whole(["run", "--adapter", "imcpy", "--message", "LblRange",
                                                           "--no-progress"], env)),
           "bare python": median_of(repeat, lambda: bare(["-c", "pass"], env)),
           "bare imcpy": median_of(repeat, lambda: bare(["-c", "import imcpy"], env))}
    out["version ratio"] = out["version"] / out["bare python"]
    out["list ratio"] = out["list"] / out["bare python"]
    out["one message ratio"] = out["one message"] / out["bare imcpy"]

    def first_run():
        with tempfile.TemporaryDirectory(prefix="imc-conformance-cache-") as cache:
            whole(["run", "--adapter", "imcpy", "--no-progress"], command_env(cache))
    out["first run"] = median_of(repeat, first_run)
    print("start-up, whole processes (medians): " + ", ".join(f"{k} {v * 1e3:.0f} ms" for k, v in out.items()
                                                              if not k.endswith("ratio"))
          + f"; --version {out['version ratio']:.1f}x and list {out['list ratio']:.1f}x a bare python, one message {out['one message ratio']:.2f}x a bare "
          "import of imcpy")
    return out

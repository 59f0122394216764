"""Start-up: whole processes of the package as a user installs it."""

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
    out["list ratio"] = out["list"] / out["bare python"]
    out["one message ratio"] = out["one message"] / out["bare imcpy"]

    def first_run():
        with tempfile.TemporaryDirectory(prefix="imc-conformance-cache-") as cache:
            whole(["run", "--adapter", "imcpy", "--no-progress"], command_env(cache))
    out["first run"] = median_of(repeat, first_run)
    print("start-up, whole processes (medians): " + ", ".join(f"{k} {v * 1e3:.0f} ms" for k, v in out.items()
                                                              if not k.endswith("ratio"))
          + f"; list {out['list ratio']:.1f}x a bare python, one message {out['one message ratio']:.2f}x a bare "
          "import of imcpy")
    return out

"""The manual (docs/, mkdocs.yml): built with ``mkdocs build --strict`` into a temporary folder, its runnable examples
run as a newcomer would run them, the built site opened in Debian's Chromium, and the report screenshot taken.

A page is run in a shell (bash) that holds only what the page set up: a clean environment (no virtual environment,
no PATH but Python's and the system's), the checkout installed by the tutorial's own commands. A block right after a
line ``<!-- setup -->`` is a ``sh`` block of commands run as written (each must exit 0). The tutorial's setup blocks
(clone, virtual environment, ``pip install`` with the extras its steps need) run once per test session, in a fresh
copy of the checkout's files, from a clean shell; its other blocks then run in the shell that left. Every other page
starts from a clean shell in the folder that holds that checkout and runs its own setup blocks (``cd``, activate).

A runnable example is a ``console`` block right after a line ``<!-- runnable -->``: each ``$ `` line is a command,
and the lines after it are what it must print, in that order, among its output (``...`` stands for anything, in a
line or as a line). The marker's ``exit=N`` is the exit code every command of the block must give (0 by default);
``port=P`` replaces the port P by a free loopback port in the block. A command ending in `` &`` runs in the
background until the page ends (then Ctrl-C), and must have printed its lines by the next command.

pip's cache is the user's (``pip cache dir``) and the suite's download cache is shared, so the install costs a build
of the suite's wheel and no download once the cache is warm."""

from __future__ import annotations

import base64
import contextlib
import fcntl
import functools
import http.server
import importlib.util
import json
import os
import re
import select
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

CHECKOUT = Path(__file__).resolve().parents[1]
DOCS = CHECKOUT / "docs"
TOOLS = DOCS / "tools"
CHROMIUM = Path("/usr/bin/chromium")
MARKER = re.compile(r"^<!-- runnable((?: \w+=\w+)*) -->\n```console\n(.*?)^```$", re.MULTILINE | re.DOTALL)
BUILD_ENV = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "PYTHONDONTWRITEBYTECODE": "1"}
needs_chromium = pytest.mark.skipif(not CHROMIUM.exists(),
                                    reason="needs Debian's chromium at /usr/bin/chromium (CI installs it)")


def tool(name: str):
    """A module of docs/tools (the site's hook, the screenshot), imported without writing bytecode beside it."""
    spec = importlib.util.spec_from_file_location(f"docs_tools_{name}", TOOLS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    before, sys.dont_write_bytecode = sys.dont_write_bytecode, True
    try:
        spec.loader.exec_module(module)
    finally:
        sys.dont_write_bytecode = before
    return module


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)], cwd=CHECKOUT,
                          env=BUILD_ENV, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-4000:]
    return out


# --- the build ----------------------------------------------------------------------------------------------------

def nav_pages() -> list[str]:
    config = (CHECKOUT / "mkdocs.yml").read_text(encoding="utf-8")
    return re.findall(r"^\s+- (?:[^:\n]+: )?(\S+\.md)$", config, re.MULTILINE)


def test_every_page_is_in_the_nav_and_built(site):
    pages = nav_pages()
    on_disk = sorted(str(p.relative_to(DOCS)) for p in DOCS.rglob("*.md") if TOOLS not in p.parents)
    assert sorted(pages) == on_disk
    for page in pages:
        built = site / ("index.html" if page == "index.md" else page.removesuffix(".md") + "/index.html")
        assert built.exists(), page


def parser_options() -> dict[str, list[str]]:
    """Every command of the command line and its option strings, from the parsers."""
    import argparse

    from imc_conformance.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return {name: [s for a in command._actions for s in a.option_strings
                   if a.help is not argparse.SUPPRESS and not isinstance(a, argparse._HelpAction)]
            for name, command in sub.choices.items()}


def test_cli_reference_holds_every_command_and_option(site):
    page = (site / "reference" / "cli" / "index.html").read_text(encoding="utf-8")
    for command, options in parser_options().items():
        assert f'id="{command}"' in page, command
        section = page.split(f'id="{command}"', 1)[1]
        for option in options:
            assert f"<code>{option}</code>" in section, (command, option)


def test_cli_reference_follows_a_renamed_option(monkeypatch):
    """The page is made from the parsers when the site is built: a renamed option is there, the old name gone."""
    reference = tool("reference")
    original = reference.build_parser

    def renamed(argv=None):
        text = "\n".join(f"{a.option_strings}" for a in original()._actions)
        assert "--no-progress" not in text  # the top-level parser; the commands' options are below
        parser = original(argv)
        sub = next(a for a in parser._actions if a.dest == "command")
        for action in sub.choices["run"]._actions:
            if "--no-progress" in action.option_strings:
                action.option_strings = ["--quiet-progress"]
        return parser

    before = reference.cli_reference()
    monkeypatch.setattr(reference, "build_parser", renamed)
    after = reference.cli_reference()
    run_before, run_after = (text.split("## `run`")[1].split("\n## ")[0] for text in (before, after))
    assert "`--no-progress`" in run_before and "`--quiet-progress`" not in run_before
    assert "`--quiet-progress`" in run_after and "`--no-progress`" not in run_after


def test_an_unknown_marker_is_an_error():
    with pytest.raises(ValueError, match="no generated part named 'nothing'"):
        tool("reference").render("# X\n\n<!-- generated: nothing -->\n", "x.md")


def test_reference_pages_are_current():
    """The generated parts are committed (a forge shows them): each is what ``make reference`` writes today."""
    reference = tool("reference")
    assert len(reference.pages()) >= 7
    stale = [str(p.relative_to(CHECKOUT)) for p in reference.stale()]
    assert not stale, f"stale reference pages, run make reference: {stale}"


def test_a_stale_reference_page_is_found(tmp_path, monkeypatch):
    reference = tool("reference")
    page = tmp_path / "cli.md"
    page.write_text(reference.render("# Command line\n\n<!-- generated: cli -->\n"), encoding="utf-8")
    monkeypatch.setattr(reference, "PAGES", tmp_path)
    assert reference.stale() == []
    page.write_text(page.read_text(encoding="utf-8").replace("--no-progress", "--quiet-progress"), encoding="utf-8")
    assert reference.stale() == [page]


# --- the runnable examples ----------------------------------------------------------------------------------------

SETUP = re.compile(r"^<!-- setup -->\n```sh\n(.*?)^```$", re.MULTILINE | re.DOTALL)
BLOCK = re.compile(rf"{SETUP.pattern}|{MARKER.pattern}", re.MULTILINE | re.DOTALL)
TUTORIAL = "tutorial.md"
CHECKOUT_NAME = "imc-conformance"  # the folder the tutorial's clone makes
COPY_IGNORE = (".git", ".venv", ".cache", "__pycache__", "*.egg-info", ".pytest_cache", ".hypothesis", "build",
               "reports", "site", "dist")


@dataclass
class Command:
    line: str
    shown: list[str] = field(default_factory=list)
    background: bool = False


@dataclass
class Example:
    page: str
    line: int
    exit: int
    commands: list[Command]
    setup: bool = False
    port: str | None = None


def examples() -> list[Example]:
    """Every setup block and runnable example of the manual, page by page, in order."""
    out = []
    for path in sorted(DOCS.rglob("*.md")):
        text = path.read_text(encoding="utf-8")
        for match in BLOCK.finditer(text):
            where = (str(path.relative_to(DOCS)), text[:match.start()].count("\n") + 1)
            if match.group(1) is not None:
                out.append(Example(*where, 0, [Command(match.group(1))], setup=True))
                continue
            options = dict(o.split("=") for o in match.group(2).split())
            commands = []
            for line in match.group(3).splitlines():
                if line.startswith("$ "):
                    background = line.rstrip().endswith(" &")
                    commands.append(Command(line[2:].rstrip().removesuffix("&").rstrip() if background else line[2:],
                                            background=background))
                else:
                    commands[-1].shown.append(line)
            out.append(Example(*where, int(options.get("exit", 0)), commands, port=options.get("port")))
    return out


EXAMPLES = examples()
PAGES = sorted({e.page for e in EXAMPLES if not e.setup})


def shown_in(shown: list[str], printed: str) -> str | None:
    """None when every shown line matches a printed line, in order; else the first that does not."""
    lines = iter(line.rstrip() for line in printed.splitlines())
    for want in shown:
        if want.strip() in ("", "..."):
            continue
        *parts, last = want.rstrip().split("...")  # a line may end where "..." begins: "got ..." matches "got"
        pattern = re.compile(".*".join([*(re.escape(part.rstrip()) for part in parts), re.escape(last)]))
        if not any(pattern.fullmatch(line) for line in lines):
            return want
    return None


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def clean_environment(home: Path) -> dict[str, str]:
    """What a newcomer's fresh shell holds: Python's and the system's folders on PATH, and nothing installed. The
    machine's pip settings and proxies are kept (how it reaches PyPI), and pip's and the suite's caches are the
    user's (speed only: what they hold is what the registries serve)."""
    user = Path.home()
    env = {"PATH": f"{Path(sys.base_prefix) / 'bin'}:/usr/local/bin:/usr/bin:/bin", "HOME": str(home),
           "LANG": "C.UTF-8", "TERM": "dumb", "COLUMNS": "200", "NO_COLOR": "1",
           "PIP_CACHE_DIR": os.environ.get("PIP_CACHE_DIR", str(user / ".cache" / "pip")),
           "IMC_CONFORMANCE_CACHE": os.environ.get("IMC_CONFORMANCE_CACHE", str(user / ".cache" / "imc-conformance"))}
    env.update({k: v for k, v in os.environ.items() if k.startswith("PIP_") or k.lower().endswith("_proxy")})
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    return env


class Shell:
    """A bash the test types into, as a reader types the page's commands: state (cd, an activated virtual
    environment) carries from one command to the next; each command's output and exit code are read back."""

    def __init__(self, cwd: Path, env: dict[str, str], logs: Path):
        self.proc = subprocess.Popen(["bash", "--noprofile", "--norc"], cwd=cwd, env=env, stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     start_new_session=True)
        self.logs, self.background, self.count, self.buffer = logs, [], 0, b""
        self.out = self.proc.stdout.fileno()  # read unbuffered: select() must see what is not yet read
        self._send("set -m")  # background jobs in groups of their own, so that Ctrl-C (SIGINT) reaches them

    def _send(self, text: str) -> None:
        self.proc.stdin.write(text + "\n")
        self.proc.stdin.flush()

    def run(self, command: str, timeout: float) -> tuple[int, str]:
        """The command's exit code and everything it printed."""
        self.count += 1
        token = f"@@done-{self.count}-{os.getpid()}"
        self._send(f"{{ {command}\n}} < /dev/null 2>&1\nprintf '\\n{token} %s\\n' $?")
        end, marker = time.monotonic() + timeout, f"\n{token} ".encode()
        while marker not in self.buffer:
            left = end - time.monotonic()
            if left <= 0 or not select.select([self.out], [], [], left)[0]:
                raise TimeoutError(f"{command!r} did not end within {timeout} s; printed:\n{self.buffer.decode(errors='replace')}")
            chunk = os.read(self.out, 1 << 16)
            if not chunk:
                raise EOFError(f"the shell ended during {command!r}; printed:\n{self.buffer.decode(errors='replace')}")
            self.buffer += chunk
        while not self.buffer.split(marker, 1)[1].count(b"\n"):  # the exit code's line, to its end
            self.buffer += os.read(self.out, 1 << 16)
        printed, rest = self.buffer.split(marker, 1)
        code, self.buffer = rest.split(b"\n", 1)
        return int(code), printed.decode(errors="replace")

    def start(self, command: str, shown: list[str], timeout: float) -> str:
        """A command run in the background (``&``); what it printed once the lines shown have appeared."""
        log = self.logs / f"background-{self.count + 1}.log"
        code, pid = self.run(f"{command} > {shlex.quote(str(log))} 2>&1 &\necho $!", timeout=10)
        self.background.append(int(pid.split()[-1]))
        end = time.monotonic() + timeout
        printed = ""
        while time.monotonic() < end:
            printed = log.read_text(errors="replace") if log.exists() else ""
            if shown_in(shown, printed) is None:
                break
            time.sleep(0.1)
        return printed

    def alive(self, pid: int) -> bool:
        return self.run(f"kill -0 {pid} 2>/dev/null", timeout=10)[0] == 0

    def close(self) -> None:
        for pid in self.background:
            try:
                os.killpg(pid, signal.SIGINT)
            except ProcessLookupError:
                continue
            end = time.monotonic() + 10
            while time.monotonic() < end and self.alive(pid):
                time.sleep(0.1)
            with contextlib.suppress(ProcessLookupError):
                os.killpg(pid, signal.SIGKILL)
        with contextlib.suppress(BrokenPipeError):
            self._send("exit")
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
        self.proc.stdin.close()
        self.proc.stdout.close()


def run_setup(shell: Shell, example: Example) -> None:
    code, printed = shell.run(example.commands[0].line, timeout=900)
    assert code == 0, f"{example.page}:{example.line}: a setup block exited {code}:\n{printed[-4000:]}"


@dataclass
class Installed:
    """The tutorial's install, done once: the folder holding the checkout and the environment its shell left."""
    work: Path
    env: dict[str, str]
    cwd: Path
    seconds: float


def _install(work: Path) -> Installed:
    """The tutorial's setup blocks from a clean shell in ``work``, where the clone is a copy of the checkout's files."""
    shutil.copytree(CHECKOUT, work / CHECKOUT_NAME, symlinks=True, ignore=shutil.ignore_patterns(*COPY_IGNORE))
    (work / "home").mkdir()
    shell = Shell(work, clean_environment(work / "home"), work)
    started = time.monotonic()
    try:
        for example in EXAMPLES:
            if example.page == TUTORIAL and example.setup:
                lines = example.commands[0].line.splitlines()
                kept = "\n".join(line for line in lines if not line.startswith("git clone "))
                run_setup(shell, Example(example.page, example.line, 0, [Command(kept)], setup=True))
        code, dump = shell.run("pwd; env -0 | base64 -w0", timeout=10)
    finally:
        shell.close()
    cwd, encoded = dump.splitlines()[-2:]
    env = dict(item.split("=", 1) for item in base64.b64decode(encoded).decode().split("\0") if "=" in item)
    for name in ("PWD", "OLDPWD", "SHLVL", "_"):
        env.pop(name, None)
    return Installed(work, env, Path(cwd), time.monotonic() - started)


@pytest.fixture(scope="session")
def installed(tmp_path_factory) -> Installed:
    """Once per test session, shared by pytest-xdist's workers (the first to come installs, under a lock)."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent
    work, state = root / "docs-install", root / "docs-install.json"
    with open(root / "docs-install.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not state.exists():
            if work.exists():
                shutil.rmtree(work)
            work.mkdir()
            done = _install(work)
            state.write_text(json.dumps({"env": done.env, "cwd": str(done.cwd), "seconds": done.seconds}))
        saved = json.loads(state.read_text())
    return Installed(work, saved["env"], Path(saved["cwd"]), saved["seconds"])


def page_folder(installed: Installed, tmp_path: Path) -> Path:
    """A folder of the page's own, laid out as the tutorial left its reader's (the checkout, its files linked), so
    that what one page writes never meets another's."""
    checkout = tmp_path / CHECKOUT_NAME
    checkout.mkdir()
    for entry in (installed.work / CHECKOUT_NAME).iterdir():
        (checkout / entry.name).symlink_to(entry, target_is_directory=entry.is_dir())
    return checkout


def test_examples_are_found():
    """The pages do hold runnable examples, each block's marker parsed, and the tutorial installs the suite."""
    runnable = [e for e in EXAMPLES if not e.setup]
    assert len(runnable) >= 8 and all(e.commands for e in runnable)
    assert {"tutorial.md", "how-to/ci.md", "how-to/live-node.md", "how-to/captures-and-logs.md"} <= set(PAGES)
    setups = [e.commands[0].line for e in EXAMPLES if e.setup and e.page == TUTORIAL]
    assert any("python3 -m venv" in s and "pip install" in s for s in setups), setups
    for page in PAGES:  # a page other than the tutorial activates the tutorial's environment itself
        assert page == TUTORIAL or any(e.setup and e.page == page and "activate" in e.commands[0].line
                                       for e in EXAMPLES), page


def test_a_clean_shell_has_no_suite(tmp_path):
    """What the pages run in holds nothing of the test's own environment: imc-conformance is not on its PATH."""
    shell = Shell(tmp_path, clean_environment(tmp_path), tmp_path)
    try:
        code, printed = shell.run("command -v imc-conformance; python3 -c 'import imc_conformance'", timeout=60)
    finally:
        shell.close()
    assert code != 0 and "No module named 'imc_conformance'" in printed, printed


@pytest.mark.parametrize("page", PAGES)
def test_runnable_page(page, installed, tmp_path):
    """Each page's blocks in order, in a shell holding only what the page (and, for the tutorial, its install) set
    up."""
    checkout = page_folder(installed, tmp_path)
    logs = tmp_path / "logs"
    logs.mkdir()
    if page == TUTORIAL:
        env, cwd = {**installed.env, "HOME": str(tmp_path)}, checkout
    else:
        env, cwd = clean_environment(tmp_path), tmp_path
    shell = Shell(cwd, env, logs)
    try:
        for example in (e for e in EXAMPLES if e.page == page):
            if example.setup:
                if page != TUTORIAL:
                    run_setup(shell, example)
                continue
            port = str(free_udp_port())
            for command in example.commands:
                line = command.line.replace(example.port, port) if example.port else command.line
                shown = [s.replace(example.port, port) for s in command.shown] if example.port else command.shown
                where = f"{page}:{example.line}: {command.line}"
                if command.background:
                    printed = shell.start(line, shown, timeout=60)
                    assert shell.alive(shell.background[-1]), f"{where}: ended:\n{printed}"
                else:
                    code, printed = shell.run(line, timeout=300)
                    assert code == example.exit, f"{where}: exit {code}, not {example.exit}:\n{printed}"
                missing = shown_in(shown, printed)
                assert missing is None, f"{where}: the page shows {missing!r}, the command printed:\n{printed}"
    finally:
        shell.close()


# --- the site in a browser ----------------------------------------------------------------------------------------

class Browser:
    """Debian's headless Chromium, driven over the DevTools protocol on a pipe (``--remote-debugging-pipe``):
    the search runs in a web worker after the page has loaded, which ``--dump-dom`` does not wait for."""

    def __init__(self, profile: Path, timeout: float = 180):
        to_browser, from_browser = os.pipe(), os.pipe()

        def child():  # the protocol's descriptors are 3 (commands) and 4 (answers)
            commands, answers = os.dup(to_browser[0]), os.dup(from_browser[1])
            os.dup2(commands, 3)
            os.dup2(answers, 4)

        self.proc = subprocess.Popen(
            [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             "--remote-debugging-pipe", f"--user-data-dir={profile}", "about:blank"],
            preexec_fn=child, pass_fds=(3, 4, to_browser[0], from_browser[1]),
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_browser[0])
        os.close(from_browser[1])
        self.out, self.inp = to_browser[1], from_browser[0]
        self.buffer, self.last_id, self.deadline = b"", 0, time.monotonic() + timeout

    def call(self, method: str, session: str | None = None, **params) -> dict:
        self.last_id += 1
        message = {"id": self.last_id, "method": method, "params": params, **({"sessionId": session} if session else {})}
        os.write(self.out, json.dumps(message).encode() + b"\0")
        while True:
            while b"\0" not in self.buffer:
                left = self.deadline - time.monotonic()
                if left <= 0 or not select.select([self.inp], [], [], left)[0]:
                    raise TimeoutError(f"chromium did not answer {method}")
                chunk = os.read(self.inp, 1 << 16)
                if not chunk:
                    raise EOFError("chromium closed its end of the pipe")
                self.buffer += chunk
            raw, self.buffer = self.buffer.split(b"\0", 1)
            reply = json.loads(raw)
            if reply.get("id") == self.last_id:
                assert "error" not in reply, reply["error"]
                return reply["result"]

    def open(self, url: str) -> str:
        target = self.call("Target.createTarget", url=url)["targetId"]
        session = self.call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        assert self.wait_for(session, "document.readyState === 'complete'"), f"{url} did not load"
        return session

    def wait_for(self, session: str, expression: str, timeout: float = 60):
        """The value of a JavaScript expression once it is truthy in the page."""
        end = time.monotonic() + timeout
        while True:
            value = self.call("Runtime.evaluate", session, expression=expression, returnByValue=True)["result"]
            if value.get("value") or time.monotonic() > end:
                return value.get("value")
            time.sleep(0.1)

    def close(self) -> None:
        self.proc.kill()
        self.proc.wait(timeout=10)
        os.close(self.out)
        os.close(self.inp)


@pytest.fixture
def served(site):
    """The built site over HTTP on loopback (the search's web worker is refused on file:// pages)."""
    handler = functools.partial(_QuietHandler, directory=str(site))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


@needs_chromium
def test_site_in_chromium(served, tmp_path):
    browser = Browser(tmp_path / "profile")
    try:
        home = browser.open(f"{served}/")
        assert browser.wait_for(home, "document.querySelector('h1') && document.querySelector('h1').innerText") \
            == "imc-conformance¶"  # the heading and its permalink
        nav = browser.wait_for(home, "Array.from(document.querySelectorAll('.md-nav__link')).map(a => a.innerText)")
        assert {"Tutorial", "Command line", "Gate CI on the suite", "Verdict policy"} <= {n.strip() for n in nav}

        cli = browser.open(f"{served}/reference/cli/")
        headings = browser.wait_for(cli, "Array.from(document.querySelectorAll('h2')).map(h => h.id)")
        assert set(parser_options()) <= set(headings)
        width = browser.wait_for(cli, "document.querySelector('.md-content').getBoundingClientRect().width")
        assert width > 300  # styled: the theme's stylesheet laid the page out

        search = browser.open(f"{served}/?q=adapter-check")
        found = browser.wait_for(search, "Array.from(document.querySelectorAll('.md-search-result__item a'))"
                                         ".map(a => a.getAttribute('href'))")
        assert any("reference/cli/" in href and href.endswith("#adapter-check") for href in found), found
        for word in ("waiver", "verdict"):  # the JSON Schemas page is kept out of the search
            hits = browser.wait_for(browser.open(f"{served}/?q={word}"),
                                    "Array.from(document.querySelectorAll('.md-search-result__item a'))"
                                    ".map(a => a.getAttribute('href'))")
            assert hits and not any("reference/schemas/" in href for href in hits), (word, hits)

        tutorial = browser.open(f"{served}/tutorial/")
        copied = browser.wait_for(tutorial, """(() => {
            const code = Array.from(document.querySelectorAll('.highlight code'))
                .find(c => c.innerText.includes('$ imc-conformance --version'));
            code.setAttribute('data-md-copying', '');  // what Material's copy button sets while it copies
            const text = code.innerText;
            code.removeAttribute('data-md-copying');
            return text;
        })()""")
        assert copied.strip() == "imc-conformance --version", repr(copied)  # the command: no prompt, no output
    finally:
        browser.close()


@needs_chromium
def test_report_screenshot(tmp_path):
    """The code that made the README's screenshot (``make screenshot``) still makes one."""
    shot = tool("screenshot").report_screenshot(tmp_path / "html-report.png", tmp_path)
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert (width, height) == tuple(int(n) for n in tool("screenshot").WINDOW.split(","))
    assert len(data) > 20_000  # a rendered report, not a blank page
    html = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert "Given (invalid, rule crc)" in html and 'data-field="footer.crc16"' in html  # the frames side by side


def test_the_report_shows_an_accepted_invalid_frame_and_counts_in_words(tmp_path, capsys):
    """What the screenshot shows, without a browser: an invalid frame pyimclsts accepted, beside what it read from
    it, the differing byte named; a header whose start time reads as a date and a time; "1 message", "1 failure"."""
    from imc_conformance.cli import main

    html, markdown = tmp_path / "r.html", tmp_path / "r.md"
    code = main(["run", "--adapter", "pyimclsts", "--id", "imc/LblRange/crc/footer-first-byte/le", "--no-progress",
                 "--html", str(html), "--markdown", str(markdown)])
    out = capsys.readouterr().out
    assert code == 1 and "1 case in " in out and "(1 failure is a documented erratum)" in out, out
    page = html.read_text(encoding="utf-8")
    assert "Given (invalid, rule crc) · 27 bytes" in page and "Read (what it decoded, encoded by the reference)" in page
    assert 'data-field="footer.crc16"' in page
    started = re.search(r'<dt>Started</dt><dd class="when">([^<]*)</dd>', page).group(1)
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d.*", started), started
    assert "**1 case** in 1 message:" in markdown.read_text(encoding="utf-8")


# --- the README, the front door -----------------------------------------------------------------------------------

def test_readme_is_a_front_door_into_the_manual():
    """Short (under 200 lines), its relative links and image all present, and it links every part of the manual."""
    text = (CHECKOUT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) < 200
    targets = re.findall(r"\]\(([^)\s#]+)(?:#[^)]*)?\)", text)
    local = [t for t in targets if not t.startswith(("http://", "https://"))]
    assert all((CHECKOUT / t).exists() for t in local), [t for t in local if not (CHECKOUT / t).exists()]
    assert {"docs/tutorial.md", "docs/how-to/ci.md", "docs/reference/cli.md", "docs/explanation/design.md",
            "docs/images/html-report.png"} <= set(local)


def test_the_waivers_page_shows_the_file_the_command_wrote():
    """how-to/waivers.md shows tests/data/pyimclsts-waivers.json (what its first example writes), which its second
    example runs with: the page's file and the tested one are the same document."""
    page = (DOCS / "how-to" / "waivers.md").read_text(encoding="utf-8")
    shown = re.search(r"^```json\n(.*?)^```$", page, re.MULTILINE | re.DOTALL).group(1)
    kept = (CHECKOUT / "tests" / "data" / "pyimclsts-waivers.json").read_text(encoding="utf-8")
    assert json.loads(shown) == json.loads(kept) and len(json.loads(kept)["waivers"]) == 7


def test_every_page_the_readme_links_is_readable_on_a_forge():
    """A forge shows the Markdown as committed: every page the README links holds text beyond its heading and
    markers (the reference pages' generated parts included)."""
    text = (CHECKOUT / "README.md").read_text(encoding="utf-8")
    pages = {t for t in re.findall(r"\]\(([^)\s#]+\.md)(?:#[^)]*)?\)", text) if not t.startswith("http")}
    assert "docs/reference/cli.md" in pages and "docs/reference/schemas.md" in pages
    for page in sorted(pages):
        body = re.sub(r"<!--.*?-->|^#.*$|^---$[\s\S]*?^---$", "", (CHECKOUT / page).read_text(encoding="utf-8"),
                      flags=re.MULTILINE)
        assert len(body.split()) > 150, f"{page}: {len(body.split())} words on a forge"


def test_the_python_adapter_shown_is_the_one_run():
    """The adapter the "write an adapter" page shows is the file its runnable example copies and runs."""
    page = (DOCS / "how-to" / "adapter.md").read_text(encoding="utf-8")
    shown = re.search(r"^```python\n(.*?)^```$", page, re.MULTILINE | re.DOTALL).group(1)
    assert shown == (DOCS / "examples" / "heartbeat_adapter.py").read_text(encoding="utf-8")

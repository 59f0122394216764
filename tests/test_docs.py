"""The manual (docs/, mkdocs.yml): built with ``mkdocs build --strict`` into a temporary folder, its runnable examples
run against the real implementations, the built site opened in Debian's Chromium, and the report screenshot taken.

A runnable example is a ``console`` block right after a line ``<!-- runnable -->``: each ``$ `` line is a command,
run without a shell from a fresh folder (``tests/data`` of the checkout reachable as ``tests/data``), and the lines
after it are what it must print, in that order, among its output (``...`` stands for anything, in a line or as a
line). The marker's ``exit=N`` is the exit code every command of the block must give (0 by default); ``port=P``
replaces the port P by a free loopback port in the block. A command ending in `` &`` runs in the background until the
block ends (then Ctrl-C), and must have printed its lines by the next command."""

from __future__ import annotations

import functools
import http.server
import importlib.util
import json
import os
import re
import select
import shlex
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
CLI = Path(sys.executable).with_name("imc-conformance")
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
        assert "<!-- generated:" not in built.read_text(encoding="utf-8"), f"{page}: a marker left unreplaced"


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

@dataclass
class Command:
    argv: list[str]
    shown: list[str] = field(default_factory=list)
    background: bool = False


@dataclass
class Example:
    page: str
    line: int
    exit: int
    commands: list[Command]


def examples() -> list[Example]:
    out = []
    for path in sorted(DOCS.rglob("*.md")):
        text = path.read_text(encoding="utf-8")
        for match in MARKER.finditer(text):
            options = dict(o.split("=") for o in match.group(1).split())
            body = match.group(2)
            if "port" in options:
                body = body.replace(options["port"], "{port}")
            commands = []
            for line in body.splitlines():
                if line.startswith("$ "):
                    argv = shlex.split(line[2:])
                    background = argv[-1] == "&"
                    commands.append(Command(argv[:-1] if background else argv, background=background))
                else:
                    commands[-1].shown.append(line)
            out.append(Example(str(path.relative_to(DOCS)), text[:match.start()].count("\n") + 1,
                               int(options.get("exit", 0)), commands))
    return out


EXAMPLES = examples()


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


def read_until_shown(proc: subprocess.Popen, shown: list[str], timeout: float) -> str:
    printed, end = "", time.monotonic() + timeout
    while shown_in(shown, printed) is not None and time.monotonic() < end:
        if select.select([proc.stdout], [], [], 0.1)[0]:
            line = proc.stdout.readline()
            if not line:
                break
            printed += line
    return printed


def test_examples_are_found():
    """The pages do hold runnable examples, and each block's marker parsed (the parametrized test runs them)."""
    assert len(EXAMPLES) >= 8 and all(e.commands for e in EXAMPLES)
    pages = {e.page for e in EXAMPLES}
    assert {"tutorial.md", "how-to/ci.md", "how-to/live-node.md", "how-to/captures-and-logs.md"} <= pages


@pytest.mark.parametrize("example", EXAMPLES, ids=[f"{e.page}:{e.line}" for e in EXAMPLES])
def test_runnable_example(example, tmp_path):
    (tmp_path / "tests").symlink_to(CHECKOUT / "tests", target_is_directory=True)
    port = str(free_udp_port())
    env = {**os.environ, "COLUMNS": "200", "NO_COLOR": "1"}
    background = []
    try:
        for command in example.commands:
            assert command.argv[0] == "imc-conformance", f"{example.page}:{example.line}: only imc-conformance runs"
            argv = [str(CLI), *(arg.replace("{port}", port) for arg in command.argv[1:])]
            shown = [line.replace("{port}", port) for line in command.shown]
            where = f"{example.page}:{example.line}: {shlex.join(command.argv)}"
            if command.background:
                proc = subprocess.Popen(argv, cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                        text=True)
                background.append(proc)
                printed = read_until_shown(proc, shown, timeout=60)
                assert proc.poll() is None, f"{where}: exited {proc.returncode}:\n{printed}"
            else:
                done = subprocess.run(argv, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
                printed = done.stdout + done.stderr
                assert done.returncode == example.exit, f"{where}: exit {done.returncode}, not {example.exit}:\n{printed}"
            missing = shown_in(shown, printed)
            assert missing is None, f"{where}: the page shows {missing!r}, the command printed:\n{printed}"
    finally:
        for proc in background:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            proc.stdout.close()


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

"""Reaching an implementation from the command line: a built-in or library adapter loaded in-process, or a
subprocess adapter started (``--adapter``, ``--adapter-cmd``, ``--adapter-arg``)."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import sys
from pathlib import Path

from ..errors import UsageError


def load_library_adapter(spec: str, suite, arguments: dict[str, str] | None = None):
    """An adapter object from a built-in name, ``module:attribute`` or ``path/to/file.py:attribute`` (an
    adapter object, a class or a factory; ``arguments`` are passed to the class or factory)."""
    builtin = suite.adapters.get(spec)
    target, _, attr = (builtin.library if builtin else spec).rpartition(":")
    if not target or not attr:
        raise UsageError(f"adapter {spec!r}: expected {', '.join(suite.adapters)}, module:attribute or "
                         "file.py:attribute (or --adapter-cmd for a subprocess)")
    try:
        if target.endswith(".py"):
            if not Path(target).is_file():
                raise UsageError(f"adapter file {target} does not exist")
            spec_ = importlib.util.spec_from_file_location(Path(target).stem, target)
            module = importlib.util.module_from_spec(spec_)
            spec_.loader.exec_module(module)
        else:
            module = importlib.import_module(target)
        target_ = getattr(module, attr)
    except UsageError:
        raise
    except ModuleNotFoundError as exc:
        raise missing_extra(builtin, exc) or UsageError(f"cannot load adapter {spec!r}: {type(exc).__name__}: {exc}") \
            from exc
    except Exception as exc:
        raise UsageError(f"cannot load adapter {spec!r}: {type(exc).__name__}: {exc}") from exc
    if hasattr(target_, "decode") and not inspect.isclass(target_):
        if arguments:
            raise UsageError(f"adapter {spec!r} is an object: it takes no --adapter-arg")
        return target_
    if not callable(target_):
        raise UsageError(f"adapter {spec!r} is a {type(target_).__name__}: expected an adapter object, "
                         "a class or a factory")
    try:  # a class or a factory
        return target_(**(arguments or {}))
    except ModuleNotFoundError as exc:  # a module imported on first use
        raise missing_extra(builtin, exc) or UsageError(f"cannot create the adapter {spec!r}: {exc}") from exc
    except Exception as exc:
        raise UsageError(f"cannot create the adapter {spec!r}: {type(exc).__name__}: {exc}") from exc


def missing_extra(builtin, exc: ModuleNotFoundError) -> UsageError | None:
    """The one line naming the pip extra a built-in adapter needs, when a module of that extra is what is missing."""
    if builtin is None or not builtin.extra or (exc.name or "imc_conformance").startswith("imc_conformance"):
        return None
    return UsageError(f"adapter {builtin.name!r} needs the {builtin.extra!r} extra, installed with the suite: "
                      f"pip install '.[{builtin.extra}]' in its checkout, or pip install 'WHEEL[{builtin.extra}]' for its "
                      f"wheel (missing module: {exc.name})")


def adapter_choice(args, suite) -> tuple[str, list[str] | None]:
    """The adapter's name and, for a subprocess adapter, its argv; usage errors for an ambiguous choice."""
    chosen = [o for o, v in (("--adapter", args.adapter), ("--adapter-cmd", args.adapter_cmd),
                             ("--adapter-socket", args.adapter_socket)) if v is not None]
    if len(chosen) > 1:
        raise UsageError(f"give one of {', '.join(chosen)}, not several")
    if args.adapter_socket is not None:
        return args.adapter_socket, None
    if args.adapter_cmd is None:
        name = args.adapter or next(iter(suite.adapters))
        return name, builtin_argv(name, suite, adapter_arguments(args))
    return args.adapter_cmd, split_command(args.adapter_cmd)


def builtin_argv(name: str, suite, arguments: dict[str, str] | None = None) -> list[str] | None:
    """The command line of a built-in subprocess adapter (a shim, or a program built on first use, which may take
    ``--adapter-arg``s), or None for a library adapter."""
    builtin = suite.adapters.get(name)
    if builtin is None or builtin.argv is None:
        return None
    from ..native import BuildError

    try:
        inspect.signature(builtin.argv).bind(**(arguments or {}))
    except TypeError:
        raise UsageError(f"adapter {name!r} takes no --adapter-arg {', '.join(arguments)}") from None
    try:
        return builtin.argv(**(arguments or {}))
    except BuildError as exc:  # a program built on first use (dune-cpp, roscpp) could not be
        raise UsageError(str(exc)) from None


def split_command(cmd: str) -> list[str]:
    """The argv of an --adapter-cmd (split like a shell would, never run by one); a usage error if there is none."""
    from ..inputs import command_argv

    try:
        return command_argv(cmd, "--adapter-cmd", "give the adapter program to run")
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def adapter_arguments(args) -> dict[str, str]:
    out = {}
    for item in args.adapter_arg:
        name, sep, value = item.partition("=")
        if not sep or not name.isidentifier():
            raise UsageError(f"--adapter-arg {item!r}: expected NAME=VALUE")
        out[name] = value
    return out


def worker_argv(name: str, suite, args) -> list[str]:
    """The command line that runs a library adapter in a worker process of its own (sessions/worker.py)."""
    return [sys.executable, "-m", "imc_conformance.sessions.worker", "--suite", suite.name, name, *args.adapter_arg]


def open_session(name: str, argv: list[str] | None, args, suite, *, isolate: bool = False):
    """The session for the chosen adapter: a subprocess when there is an argv, else a library adapter (in a worker
    process if ``isolate``); either also runs the scenarios of a handler it calls (sessions/calls.py)."""
    from ..sessions.calls import CallTarget
    from ..sessions.library import LibrarySession

    if getattr(args, "adapter_socket", None) is not None:  # fuzz has no --adapter-socket
        from ..sessions.stream_socket import SocketSession

        if args.adapter_arg:
            raise UsageError("--adapter-arg is for library adapters; a socket adapter takes its own arguments")
        try:
            return CallTarget(SocketSession(args.adapter_socket, encoding_param=suite.encoding_param,
                                            timeout=args.timeout, hello_timeout=max(30.0, args.timeout)))
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    if argv is None and isolate:
        load_library_adapter(name, suite, adapter_arguments(args))  # a one-line error now, not a dead worker later
        argv = worker_argv(name, suite, args)
    elif argv is not None and args.adapter_arg and name not in suite.adapters:
        adapter_arguments(args)  # NAME=VALUE, checked
        argv = [*argv, *args.adapter_arg]  # a program's last arguments, as the worker takes them (e.g. path=transport)
    if argv is not None:
        from ..sessions.subprocess import SubprocessSession

        return CallTarget(SubprocessSession(argv, name=name, encoding_param=suite.encoding_param, timeout=args.timeout,
                                            hello_timeout=max(30.0, args.timeout),  # start-up (a JVM, class generation) takes longer
                                            memory_limit=args.memory_limit * 1024 * 1024))
    return CallTarget(LibrarySession(load_library_adapter(name, suite, adapter_arguments(args)), name))


def started_session(args, suite):
    """(name, session) of the chosen adapter, started and greeted; usage errors if it cannot be."""
    from ..core.session import AdapterStartError

    name, argv = adapter_choice(args, suite)
    session = open_session(name, argv, args, suite)
    try:
        session.hello()
    except AdapterStartError as exc:
        session.close()
        raise UsageError(str(exc)) from exc
    return name, session

"""The package's .msg and .srv files of an edition, written from the definitions (what a ROS 1 build reads)."""

from __future__ import annotations

import os
from pathlib import Path

from ...inputs import read_text
from .definitions import DefinitionError, Edition
from .msgtext import msg_text, parse_msg


def package_texts(edition: Edition, package: str = "ros_acomms_msgs",
                  lone_halves: bool = False) -> tuple[dict[str, str], list[str]]:
    """``{"msg/CST.msg": text, "srv/PingModem.srv": text, ...}`` for the package's types in ``edition``, and the
    services left out because the edition lacks one of their halves (with ``lone_halves``, the half it has is
    written as a message of its name instead: same type name and MD5, no service)."""
    texts, services, left_out = {}, {}, []
    for message in edition.types.values():
        d = message.definition
        if d.package != package:
            continue
        if d.kind == "msg":
            texts[f"msg/{d.name}.msg"] = msg_text(message)
        else:
            services.setdefault(d.service, {})[d.kind] = message
    for service, halves in services.items():
        if set(halves) == {"request", "response"}:
            texts[f"srv/{service}.srv"] = msg_text(halves["request"]) + "---\n" + msg_text(halves["response"])
        elif lone_halves:
            texts.update({f"msg/{m.name}.msg": msg_text(m) for m in halves.values()})
        else:
            left_out.append(f"{service}.srv")
    return texts, left_out


def write_package(edition: Edition, folder: Path, replace: bool = False) -> tuple[list[Path], list[str]]:
    """Write the edition's files under ``folder`` (``msg/``, ``srv/``, created if need be); ValueError with one
    line, before anything is written, if a file is there already (unless ``replace``) or a folder is not one.
    Nothing is written through a symbolic link: a new file is created exclusively, a replaced one swapped in."""
    texts, left_out = package_texts(edition)
    folder = Path(folder)
    paths = {name: folder / name for name in texts}
    for sub in {folder, *(p.parent for p in paths.values())}:
        if sub.is_symlink() and sub != folder:
            raise ValueError(f"{sub} is a symbolic link: the files go into real folders only")
        if sub.exists() and not sub.is_dir():
            raise ValueError(f"{sub} is not a folder")
    present = [p for p in paths.values() if p.exists() or p.is_symlink()]
    if present and not replace:
        raise ValueError(f"{len(present)} of the files are there already (e.g. {present[0]}): give --replace to "
                         "replace them, or another folder")
    written = []
    try:
        for name, text in texts.items():
            path = paths[name]
            path.parent.mkdir(parents=True, exist_ok=True)
            _write_new(path.with_name(path.name + ".new") if replace else path, text.encode("utf-8"))
            if replace:
                os.replace(path.with_name(path.name + ".new"), path)  # swaps a link for the file, never writes through
            written.append(path)
    except OSError as exc:
        raise ValueError(f"cannot write under {folder}: {exc.strerror or exc}"
                         + (f" ({exc.filename})" if exc.filename else "")) from None
    return written, left_out


def _write_new(path: Path, data: bytes) -> None:
    """Create ``path`` (it must not exist, not even as a link) and write ``data``."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644)
    with os.fdopen(fd, "wb") as out:
        out.write(data)


def read_package(folder: Path, package: str = "ros_acomms_msgs") -> dict[str, str]:
    """Type name -> .msg text of a team's package folder: ``msg/*.msg``, and each ``srv/*.srv`` as its
    ``<Name>Request`` and ``<Name>Response``. Every text is parsed; ValueError names the file and line of a
    syntax error (ROS tools differ in what they tolerate)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"{folder}: no such directory")
    found = [(path.stem, read_text(path), path) for path in sorted(folder.glob("msg/*.msg"))]
    for path in sorted(folder.glob("srv/*.srv")):
        request, sep, response = read_text(path).partition("\n---")
        if not sep:
            raise ValueError(f"{path}: a .srv needs a '---' line between request and response")
        found += [(f"{path.stem}Request", request + "\n", path), (f"{path.stem}Response", response.partition("\n")[2], path)]
    if not found:
        raise ValueError(f"{folder}: no msg/*.msg or srv/*.srv files")
    for _, text, path in found:
        try:
            parse_msg(text, package, f"{path}: ")
        except DefinitionError as exc:
            raise ValueError(str(exc)) from None
    return {name: text for name, text, _ in found}


def source_files(edition: str | None, msgs: str | None, package: str = "ros_acomms_msgs") -> dict[str, str]:
    """Relative path -> text of the msg/ and srv/ files a code generator (genpy, gencpp) reads: a team's package
    folder ``msgs`` (checked line by line first, so a syntax error is named by file and line), else the suite's
    edition (the seed's by default; a service half without the other half as a message of the same name)."""
    if msgs is not None:
        folder = Path(msgs)
        read_package(folder, package)
        return {p.relative_to(folder).as_posix(): p.read_text(encoding="utf-8")
                for p in sorted([*folder.glob("msg/*.msg"), *folder.glob("srv/*.srv")])}
    from .definitions import load_definitions

    return package_texts(load_definitions().edition(edition or "seed"), package, lone_halves=True)[0]


def generated_package(tool: str, package: str, root: Path, versions: dict, files: dict[str, str], make,
                      *key) -> Path:
    """The folder (``gen``) a ROS 1 code generator of Debian's (genpy, gencpp: unpacked in ``root``) made from the
    package's text ``files``, once per text, package versions and ``key``, in ``<cache>/<tool>-classes/<hash>``,
    one process at a time: ``make(src, gen, env, includes)`` runs the generator on the files written under ``src``,
    with ``env`` finding Debian's genmsg and ``includes`` the package's and std_msgs' message folders."""
    from ...cache import cache_dir
    from ...native import digest, locked

    out = cache_dir() / f"{tool}-classes" / digest(versions, files, *key)
    src, gen = out / "src", out / "gen"
    if (out / "done").exists():
        return gen
    with locked(out):
        if not (out / "done").exists():
            for name, text in files.items():
                (src / name).parent.mkdir(parents=True, exist_ok=True)
                (src / name).write_text(text, encoding="utf-8")
            env = {**os.environ, "PYTHONPATH": str(root / "usr/lib/python3/dist-packages")}
            includes = ["-I", f"{package}:{src / 'msg'}", "-I", f"std_msgs:{root / 'usr/share/std_msgs/msg'}"]
            make(src, gen, env, includes)
            (out / "done").write_text("", encoding="utf-8")
    return gen

"""The package's .msg and .srv files of an edition, written from the definitions (what a ROS 1 build reads)."""

from __future__ import annotations

from pathlib import Path

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


def write_package(edition: Edition, folder: Path) -> tuple[list[Path], list[str]]:
    texts, left_out = package_texts(edition)
    written = []
    for name, text in texts.items():
        path = Path(folder) / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
        written.append(path)
    return written, left_out


def read_package(folder: Path, package: str = "ros_acomms_msgs") -> dict[str, str]:
    """Type name -> .msg text of a team's package folder: ``msg/*.msg``, and each ``srv/*.srv`` as its
    ``<Name>Request`` and ``<Name>Response``. Every text is parsed; ValueError names the file and line of a
    syntax error (ROS tools differ in what they tolerate)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"{folder}: no such directory")
    found = [(path.stem, path.read_text(encoding="utf-8"), path) for path in sorted(folder.glob("msg/*.msg"))]
    for path in sorted(folder.glob("srv/*.srv")):
        request, sep, response = path.read_text(encoding="utf-8").partition("\n---")
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

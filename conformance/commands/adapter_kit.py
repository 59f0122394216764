"""``imc-conformance adapter-kit LANGUAGE DIR``: a starter adapter in LANGUAGE and the adapter contract, copied out of
the installed package into a new folder, to be built, checked with adapter-check and filled in from there."""

from __future__ import annotations

from ..errors import UsageError

CONTRACT_NAME = "ADAPTER-CONTRACT.md"  # the contract's name in the kit; the starters' READMEs link to it


def languages() -> list[str]:
    from ..paths import STARTERS

    return sorted(p.name for p in STARTERS.iterdir() if (p / "README.md").is_file())


def add(sub) -> None:
    kit = sub.add_parser("adapter-kit", help="copy a starter adapter and the adapter contract into a new folder")
    kit.add_argument("language", choices=languages(), metavar="LANGUAGE",
                     help=f"the starter's language: {', '.join(languages())}")
    kit.add_argument("folder", metavar="DIR", help="the folder to write (new, or empty)")
    kit.set_defaults(func=command)


def command(args) -> int:
    from pathlib import Path

    from ..escaping import printable
    from ..paths import CONTRACT, STARTERS

    source, folder = STARTERS / args.language, Path(args.folder)
    files = sorted(p for p in source.rglob("*") if p.is_file() and "__pycache__" not in p.parts)
    try:
        if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
            raise UsageError(f"{args.folder}: {'not empty' if folder.is_dir() else 'exists and is not a folder'}"
                             ": adapter-kit writes into a new or empty folder")
        for path in files:
            target = folder / path.relative_to(source)
            target.parent.mkdir(parents=True, exist_ok=True)
            text = path.read_bytes()
            if path.name == "README.md":  # the contract beside it, not two folders up as in the package
                text = text.replace(b"](../../README.md)", f"]({CONTRACT_NAME})".encode())
            target.write_bytes(text)
        (folder / CONTRACT_NAME).write_bytes(CONTRACT.read_bytes())
    except OSError as exc:
        raise UsageError(f"{args.folder}: cannot write the kit: {exc.strerror or exc}") from None
    print(f"{printable(args.folder)}: the {args.language} starter ({len(files)} files) and the adapter contract "
          f"({CONTRACT_NAME}); its README.md says how to build it, check it with adapter-check and run the suite on it")
    return 0

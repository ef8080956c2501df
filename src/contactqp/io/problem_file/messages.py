"""Messages of a problem file: one line that starts with the TOML file and names the key."""

from __future__ import annotations

import difflib
from pathlib import Path

from ...errors import InvalidInputError

__all__ = ["Where", "one_line", "describe", "counted", "close_match", "check_keys", "as_table"]


def one_line(text) -> str:
    """Collapse a message to one line."""
    return "; ".join(part.strip() for part in str(text).splitlines() if part.strip())


class Where:
    """Prefixes messages with the TOML file and raises the errors of one problem file."""

    def __init__(self, path: Path):
        self.path = path
        self.base = path.parent

    def error(self, key: str, message: str, cls=InvalidInputError) -> Exception:
        """An exception of class ``cls`` whose message names the file and ``key``."""
        message = str(message)
        if not key:
            text = f"{self.path}: {message}"
        elif message.startswith("has "):  # reads as a sentence: "[loads].values has 4 entries"
            text = f"{self.path}: {key} {message}"
        else:
            text = f"{self.path}: {key}: {message}"
        return cls(one_line(text))

    def rewrap(self, key: str, exc: Exception) -> Exception:
        """``exc`` raised again with ``key`` as a prefix, keeping its class."""
        message = one_line(f"{self.path}: {key}: {exc}")
        try:
            return type(exc)(message)
        except Exception:  # an exception class with an unusual constructor
            return InvalidInputError(message)


def close_match(name: str, allowed) -> str:
    """``"; did you mean 'x'?"`` for the allowed name closest to ``name``, else ``""``."""
    guesses = difflib.get_close_matches(name, list(allowed), n=1)
    return f"; did you mean '{guesses[0]}'?" if guesses else ""


def check_keys(where: Where, table: dict, allowed, key: str) -> None:
    """Raise, naming ``key`` and the allowed keys, on the first key of ``table`` not allowed."""
    for name in table:
        if name not in allowed:
            raise where.error(
                key,
                f"unknown key '{name}' (allowed: {', '.join(sorted(allowed))})"
                f"{close_match(name, allowed)}",
            )


def as_table(where: Where, value, key: str) -> dict:
    """``value`` when it is a TOML table, else an error naming ``key``."""
    if not isinstance(value, dict):
        raise where.error(key, f"must be a table, got {describe(value)}")
    return value


def describe(value) -> str:
    """What a TOML value is, for a message (``"the string 'x'"``, ``"a table"``, ...)."""
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    if isinstance(value, list):
        return f"an array of {len(value)} entries"
    if isinstance(value, dict):
        return "a table"
    return f"a {type(value).__name__}"


def counted(n: int, word: str, plural: str | None = None) -> str:
    """``"1 node"``, ``"3 nodes"``."""
    return f"{n} {word}" if n == 1 else f"{n} {plural or word + 's'}"

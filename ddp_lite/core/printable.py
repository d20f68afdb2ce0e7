"""Names that come from others (a student's folder, a hand-in's file name), shown on a terminal or in a log
as the characters they are, never as what they would make a terminal do.

:func:`printable` writes each character that is not printable as its Python escape: ESC (a terminal
escape that recolours, moves the cursor or retitles the window), a carriage return or a line break (a
fake line in the log), a right-to-left override (the rest of the line reversed), a zero-width or a
no-break space (two names that look alike). Standard library only.

Example:
    >>> printable("ada\\x1b[2J")
    'ada\\\\x1b[2J'
"""
from __future__ import annotations

__all__ = ["printable"]


def printable(text) -> str:
    """``str(text)`` with every non-printable character (``str.isprintable``; the space is kept) written as
    its escape (``\\x1b``, ``\\n``, ``\\u202e``); a printable text is returned unchanged."""
    text = str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)

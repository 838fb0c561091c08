"""What the ``twin`` command prints where the terminal cannot encode its text.

The twin's text has a few characters beyond ASCII (``°``, ``§``, ``²``, ``±``, ...). Under a
locale that is not UTF-8 (``LC_ALL=C`` with Python's UTF-8 mode and locale coercion off),
Python writes stdout and stderr in ASCII and would fail on the first ``°``. :func:`fit_streams`
makes such a stream write an ASCII spelling instead (``deg``, ``S``, ``^2``, ``+/-``) and ``?``
for anything else; a stream that can encode the text is left as it is. Files are another
matter: the twin reads and writes them in UTF-8 whatever the locale.

Examples
--------
>>> "12.5° (§3.3.4)".encode("ascii", errors=ERRORS)
b'12.5deg (S3.3.4)'

"""

from __future__ import annotations

import codecs
import contextlib
from collections.abc import Mapping
from typing import TextIO

#: ASCII spellings of the characters the twin prints.
ASCII: Mapping[str, str] = {
    "°": "deg", "§": "S", "²": "^2", "³": "^3", "±": "+/-", "×": "x", "µ": "u", "é": "e",
    "→": "->", "…": "...", "χ": "chi", "≈": "~", "≤": "<=", "≥": ">=", "–": "-", "—": "-",
    "’": "'", "‘": "'", "“": '"', "”": '"', "τ": "tau", "ω": "omega", "Δ": "delta",
}  # fmt: skip
#: The name of the error handler (:func:`codecs.register_error`) that writes them.
ERRORS = "twin-ascii"
#: Text a stream must encode to be left as it is.
SAMPLE = "".join(ASCII)


def _byte(c: str) -> bytes:
    """Return the bytes written for a character the stream cannot encode.

    A lone surrogate (a byte of a command-line argument or file name that was not text in the
    locale's encoding) is written back as that byte; anything else as its ASCII spelling.
    """
    if 0xDC80 <= ord(c) <= 0xDCFF:
        return bytes([ord(c) - 0xDC00])
    return ASCII.get(c, "?").encode("ascii")


def _ascii(error: UnicodeError) -> tuple[bytes, int]:
    """Replace what cannot be encoded by its ASCII spelling (``?`` if none)."""
    if not isinstance(error, UnicodeEncodeError):
        raise error
    bad = error.object[error.start : error.end]
    return b"".join(_byte(c) for c in bad), error.end


codecs.register_error(ERRORS, _ascii)


def encodes(stream: TextIO, text: str = SAMPLE) -> bool:
    """Whether ``stream``'s encoding can write ``text`` (a stream without one: assumed so)."""
    encoding = getattr(stream, "encoding", None)
    if not encoding:
        return True
    try:
        text.encode(encoding)
    except UnicodeEncodeError:
        return False
    except LookupError:  # an encoding Python does not know: leave the stream alone
        return True
    return True


def fit_streams(*streams: TextIO) -> None:
    """Make each stream that cannot encode the twin's text write ASCII spellings instead.

    Parameters
    ----------
    *streams : TextIO
        Typically ``sys.stdout`` and ``sys.stderr``; one without ``reconfigure`` (a test's
        :class:`io.StringIO`) or one that encodes the text is left as it is.

    """
    for stream in streams:
        if not encodes(stream):
            with contextlib.suppress(AttributeError, ValueError, OSError):
                stream.reconfigure(errors=ERRORS)  # type: ignore[attr-defined]

"""The one error type for mistakes a user can fix (a bad prompt, length, name or path): every entry point prints it
as one line naming the fix and exits with code 2, and the library raises it wherever input is checked."""

from __future__ import annotations


class UsageError(ValueError):
    """A mistake the user can fix (bad prompt, length, name, path); printed as one line, exit code 2."""

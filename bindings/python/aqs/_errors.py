"""Exceptions: one class per aqs_status code (private module; re-exported)."""

import builtins

from . import _lib


class Error(Exception):
    """A libaqs call returned a non-OK aqs_status.

    Attributes: status (the negative code), status_name ("AQS_EINVAL", ...),
    message (aqs_linkage_last_error: names the function, argument and value).
    """

    status = None

    def __init__(self, message, status=None):
        if status is not None:
            self.status = status
        self.message = message
        self.status_name = _lib.STATUS_NAMES.get(self.status, "status %s" % (self.status,))
        super().__init__(message)

    def __str__(self):
        return "%s [%s]" % (self.message, self.status_name) if self.message else self.status_name


class InvalidArgument(Error, ValueError):
    """AQS_EINVAL: an argument is invalid (NULL, non-finite, out of its domain)."""

    status = _lib.EINVAL


class RangeError(Error, IndexError):
    """AQS_ERANGE: a body or joint index is out of range."""

    status = _lib.ERANGE


class StateError(Error, RuntimeError):
    """AQS_ESTATE: wrong phase (adding after finalize, solving before; closed linkage)."""

    status = _lib.ESTATE


class OutOfMemoryError(Error, builtins.MemoryError):
    """AQS_ENOMEM: an allocation failed; the linkage is unchanged (a solve's hand-over to
    the exact DCA also discards the previous results: docs/api.md, "Memory")."""

    status = _lib.ENOMEM


class ModelError(Error, ValueError):
    """AQS_EMODEL: finalize found the linkage invalid (topology, mass)."""

    status = _lib.EMODEL


class NumericError(Error, ArithmeticError):
    """AQS_ENUMERIC: a numerical failure (singular articulated inertia)."""

    status = _lib.ENUMERIC


class SizeError(Error, ValueError):
    """AQS_ESIZE: an array has the wrong size; nothing was written."""

    status = _lib.ESIZE


# Shown as aqs.SizeError etc. in tracebacks: the name users import them by.
for _cls in (Error, InvalidArgument, RangeError, StateError, OutOfMemoryError, ModelError,
             NumericError, SizeError):
    _cls.__module__ = "aqs"
del _cls

BY_STATUS = {cls.status: cls for cls in (InvalidArgument, RangeError, StateError,
                                         OutOfMemoryError, ModelError, NumericError, SizeError)}


def from_status(status, message):
    """The exception for a non-OK status (Error itself for an unknown code)."""
    cls = BY_STATUS.get(status)
    if cls is None:
        return Error(message, status)
    return cls(message)

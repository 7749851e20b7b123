# SPDX-License-Identifier: BSD-3-Clause
"""Output files the way the C++ tools write them (frontend/include/cylfe/output_file.hpp): a
regular file is written as PATH.part and renamed over PATH when complete, so a failed run never
leaves a partial file in place of a good one; a device node or FIFO (`/dev/null`, a named pipe) is
written in place and never replaced; a symbolic link is written through to its file (the link
stays); a dangling link or a directory is refused."""
from __future__ import annotations

import os
import stat


class OutputError(ValueError):
    """An output path that must not be written; the message names it."""


class OutputFile:
    def __init__(self, path: str, mode: str = "wb"):
        self.path = path
        if os.path.islink(path) and not os.path.exists(path):
            raise OutputError(f"{path}: a dangling symbolic link; not written")
        target = os.path.realpath(path) if os.path.islink(path) else path
        if os.path.isdir(target):
            raise OutputError(f"{path}: is a directory")
        self._in_place = os.path.exists(target) and not stat.S_ISREG(os.stat(target).st_mode)
        self._target = target
        self._tmp = target if self._in_place else target + ".part"
        self.f = open(self._tmp, mode)

    def close(self):
        """Finish: rename the temporary file over the target (a regular file or none)."""
        if self.f is None:
            return
        self.f.close()
        self.f = None
        if not self._in_place:
            os.replace(self._tmp, self._target)

    def abort(self):
        """Stop without touching the target (the temporary file is removed)."""
        if self.f is not None:
            self.f.close()
            self.f = None
            if not self._in_place:
                os.unlink(self._tmp)

    def __enter__(self):
        return self.f

    def __exit__(self, exc_type, *a):
        if exc_type is None:
            self.close()
        else:
            self.abort()

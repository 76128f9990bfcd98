"""Filling a real filesystem to its last byte: the full-disk tests of the study logs
(tests/study/test_full_disk.py) and of the hub's database (tests/course/test_hub.py) share it."""

from __future__ import annotations

import errno
import os


def fill_filesystem(folder) -> os.PathLike:
    """Fills the filesystem holding ``folder`` to its last byte; the filler, to remove when space returns."""
    filler = folder / "filler"
    fd = os.open(filler, os.O_WRONLY | os.O_CREAT)
    try:
        block = b"\0" * 4096
        while True:
            try:
                os.write(fd, block)
            except OSError as error:
                assert error.errno == errno.ENOSPC
                break
        for size in (512, 64, 8, 1):  # the last page's remainder too
            try:
                while True:
                    os.write(fd, b"\0" * size)
            except OSError:
                pass
    finally:
        os.close(fd)
    return filler

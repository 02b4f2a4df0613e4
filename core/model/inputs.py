"""Reading an input file: only regular files, never blocking, never unbounded.

A FIFO named as the program would block ``open`` forever, ``/dev/zero`` would be read until
memory runs out, a folder gives an OS error in the middle of parsing. Every reader (programs,
subprograms, CL data, traces, machine files, tool tables) reads through :func:`read_input`,
which opens without blocking, checks that what it opened is a regular file and that it is
not larger than :data:`MAX_INPUT_BYTES`, and turns every OS error into an
:class:`InputError` naming the file.
"""

from __future__ import annotations

import os
import stat

from core.model.errors import InputError

#: Largest input file read: 1 GiB. A 5,000,000-block finishing program is about 150 MB; a
#: day of 1 ms trace samples about 2 GB of CSV -- recordings that long are cut by the user.
MAX_INPUT_BYTES = 1 << 30
#: Bytes read at a time: a file of up to this size is one read, its bytes taken as they
#: come (b"".join of one chunk is that chunk: no copy).
READ_CHUNK = 1 << 28

_KINDS = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISLNK, "a symbolic link"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISSOCK, "a socket"),
)


def file_kind(mode: int) -> str:
    """What a file that is not a regular file is, for messages ("a FIFO", "a folder"...)."""
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def read_input(
    path: str | os.PathLike[str], *, limit: int | None = None, what: str = "input"
) -> bytes:
    """The bytes of the regular file ``path`` (at most ``limit`` bytes when given: the head
    a reader sniffs). Raises :class:`InputError` naming the file for anything else."""
    name = str(path)
    try:
        # O_NONBLOCK: opening a FIFO without a writer returns at once instead of waiting.
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0))
    except IsADirectoryError:
        raise InputError(f"is a folder, not {what}", source=name) from None
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", source=name) from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise InputError(f"is {file_kind(st.st_mode)}, not {what}", source=name)
        if limit is None and st.st_size > MAX_INPUT_BYTES:
            raise InputError(
                f"{st.st_size:,} bytes: larger than the {MAX_INPUT_BYTES >> 20:,} MiB ncperf reads",
                source=name,
            )
        want = st.st_size if limit is None else min(limit, st.st_size)
        chunks, got = [], 0
        while got < want:
            b = os.read(fd, min(want - got, READ_CHUNK))
            if not b:
                break  # the file shrank while being read
            chunks.append(b)
            got += len(b)
        return b"".join(chunks)
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", source=name) from None
    finally:
        os.close(fd)


def read_input_text(path: str | os.PathLike[str], *, what: str = "input") -> str:
    """:func:`read_input` decoded as UTF-8; a byte that is not UTF-8 is an error at its line."""
    raw = read_input(path, what=what)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise InputError("not a UTF-8 text file", source=str(path), line=line) from None

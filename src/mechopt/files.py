"""Writing files so that nothing is ever half-written: a temporary file `<name>.<pid>.tmp` beside
the target, flushed to disk, renamed over it, and the folder synced (a reader sees the old file or
the new one, even after a power cut; a sweep removes temporaries a killed writer left)."""
import errno
import os
import stat
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

try:                                 # Unix; Windows locks with msvcrt (the package imports on both)
    import fcntl
except ImportError:
    fcntl = None


def write_bytes_atomic(path, data: bytes) -> Path:
    """`data` into `path` whole or not at all (parent folders created); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    folder = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(folder)               # the rename itself survives a power cut
    finally:
        os.close(folder)
    return path


def write_text_atomic(path, text: str) -> Path:
    """`text` (UTF-8) into `path` whole or not at all; returns the path."""
    return write_bytes_atomic(path, text.encode("utf-8"))


_SHIPPED: ContextVar[dict] = ContextVar("mechopt_shipped", default={})     # resolved path -> bytes
_RECORDERS: ContextVar[tuple] = ContextVar("mechopt_recorders", default=())


@contextmanager
def recorded():
    """A dict that collects every file `read_regular` reads inside the block (resolved path ->
    bytes): what a scene references, to be sent with it to a worker on another machine."""
    got = {}
    token = _RECORDERS.set(_RECORDERS.get() + (got,))
    try:
        yield got
    finally:
        _RECORDERS.reset(token)


@contextmanager
def shipped(files: dict):
    """Inside the block, `read_regular` takes these files (resolved path -> bytes, from
    `recorded` on the client) instead of the disk: a worker elsewhere has no copy of them."""
    token = _SHIPPED.set({**_SHIPPED.get(), **files})
    try:
        yield
    finally:
        _SHIPPED.reset(token)


def read_regular(path, *, max_bytes: int, what: str) -> bytes:
    """The bytes of `path`, refused unless it is a regular file of at most `max_bytes` bytes read
    (`what` names it in the message: "a scene file")
    (not as `st_size` says: /dev/zero reports 0 and never ends; a FIFO would block forever).
    Raises OSError (a missing or unreadable file) or ValueError naming `what` and the limit."""
    key = str(real_path(path))
    data = _SHIPPED.get().get(key)
    if data is None:
        data = _read_regular(path, max_bytes, what)
    for got in _RECORDERS.get():
        got[key] = data
    return data


def real_path(path) -> Path:
    """`path` with its symbolic links followed as far as they go. A loop of links is left for
    open() to refuse (ELOOP: one clear line), where Path.resolve raises RuntimeError (Python < 3.13)."""
    return Path(os.path.realpath(path))


def _read_regular(path, max_bytes, what):
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    fd = os.open(path, flags)          # non-blocking: opening a FIFO with no writer returns at once
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = ("folder" if stat.S_ISDIR(mode) else "FIFO" if stat.S_ISFIFO(mode)
                    else "socket" if stat.S_ISSOCK(mode) else "device")
            raise ValueError(f"{path}: a {kind}, not {what} (references must name regular files)")
        size = os.fstat(fd).st_size
        if size > max_bytes:         # said before reading; the count below holds if the file grows meanwhile
            raise ValueError(f"{path}: {size / 1e6:.3g} MB; {what} is at most {max_bytes / 1e6:g} MB")
        chunks, total = [], 0
        while chunk := os.read(fd, min(1 << 20, max_bytes + 1 - total)):
            chunks.append(chunk)
            total += len(chunk)
            if total > max_bytes:
                raise ValueError(f"{path}: more than {max_bytes / 1e6:g} MB; {what} is at most {max_bytes / 1e6:g} MB")
        return b"".join(chunks)
    finally:
        os.close(fd)


def quote(value, limit: int = 40) -> str:
    """A short, escaped prefix of a value read from a file: an error names the file and line but
    echoes no more of its content (a reference may name a key file or /etc/passwd)."""
    try:
        text = repr(value)
    except RecursionError:
        return "(a value nested too deeply to show)"
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def take_lock(path) -> int | None:
    """An open descriptor holding an exclusive lock on the file `path` (created if absent), or None
    when another process holds it. A symbolic link, folder, FIFO or device at `path` is refused
    (ValueError), never followed: a lock is written to, and a link would make it truncate its target.
    A lock its holder removed as we opened it is let go and the new file taken (`holds`)."""
    while True:
        fd = _lock_once(Path(path))
        if fd is None or holds(fd, path):
            return fd
        os.close(fd)


def _lock_once(path):
    if path.is_symlink():
        raise ValueError(f"{path}: a symbolic link where a lock file belongs; remove it (it is not followed)")
    flags = os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, flags, 0o644)
    except OSError as exc:
        if exc.errno in (errno.ELOOP, errno.EISDIR):
            raise ValueError(f"{path}: not a regular file where a lock file belongs; remove it") from None
        raise
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise ValueError(f"{path}: not a regular file (a FIFO, device or socket) where a lock file belongs; "
                             "remove it")
        if fcntl is not None:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        else:
            import msvcrt
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
    except OSError as exc:
        os.close(fd)
        if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EDEADLK):
            return None
        raise
    except BaseException:
        os.close(fd)
        raise
    return fd


def holds(fd: int, path) -> bool:
    """Whether the locked descriptor `fd` is still the file at `path` (not deleted or replaced)."""
    try:
        now = os.stat(path, follow_symlinks=False)
    except FileNotFoundError:
        return False
    mine = os.fstat(fd)
    return (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino)

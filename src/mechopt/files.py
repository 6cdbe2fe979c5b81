"""Writing files so that nothing is ever half-written: a temporary file beside the target, created
exclusively under an unpredictable name (`.<name>.<16 hex>.tmp`: a link or folder planted there is
never followed or opened), flushed to disk, renamed over the target, and the folder synced (a
reader sees the old file or the new one, even after a power cut). Only the temporary a call
created is ever removed by it."""
import errno
import os
import re
import secrets
import stat
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

try:                                 # Unix; Windows locks with msvcrt (the package imports on both)
    import fcntl
except ImportError:
    fcntl = None

NAME_ROOM = 100                  # characters of a target's name kept in its temporary's (a name has <= 255)
NAME_MAX = 255                   # bytes in one file name on every file system mechopt writes to
_TEMPORARY = re.compile(r"\.(.+)\.[0-9a-f]{16}\.tmp")


class NotWritten(OSError):
    """An output could not be written (its folder made, its file created or renamed into place);
    `filename` names the output, not its temporary."""


def write_bytes_atomic(path, data: bytes, *, replace: bool = True, on_temporary=None) -> Path:
    """`data` into `path` whole or not at all (parent folders created); returns the path.

    `replace=False` never replaces an existing file (FileExistsError, nothing written).
    `on_temporary(path)` is told the temporary's name as soon as it exists (a sweep records it,
    to remove it after a kill). Any OSError is raised as NotWritten naming `path`."""
    path = Path(path)
    make_folder(path.parent)
    try:
        fd, tmp = _create_temporary(path)
    except OSError as exc:
        raise NotWritten(exc.errno, exc.strerror or str(exc), str(path)) from exc
    try:
        with os.fdopen(fd, "wb") as f:
            if on_temporary is not None:
                on_temporary(tmp)
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        (os.replace if replace else _link_new)(tmp, path)
    except BaseException as exc:
        tmp.unlink(missing_ok=True)      # ours: created exclusively above
        if isinstance(exc, OSError) and not isinstance(exc, (NotWritten, FileExistsError)):
            raise NotWritten(exc.errno, exc.strerror or str(exc), str(path)) from exc
        raise
    _sync_folder(path.parent)
    return path


def write_text_atomic(path, text: str, **how) -> Path:
    """`text` (UTF-8) into `path` whole or not at all; returns the path (`how`: as write_bytes_atomic)."""
    return write_bytes_atomic(path, text.encode("utf-8"), **how)


def make_folder(folder) -> Path:
    """`folder` and its parents (NotWritten naming it when that fails)."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise NotWritten(exc.errno, exc.strerror or str(exc), str(folder)) from exc
    return folder


def temporary_target(name: str) -> str | None:
    """The (shortened) target name of a temporary named by `write_bytes_atomic`, or None when
    `name` is not one."""
    got = _TEMPORARY.fullmatch(name)
    return got[1] if got else None


def _create_temporary(path):
    """(descriptor, path) of a new, empty file beside `path`: O_EXCL and O_NOFOLLOW, so a link,
    file or folder already at a guessed name is never opened (another name is drawn)."""
    flags = (os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
             | getattr(os, "O_CLOEXEC", 0))
    for _ in range(100):
        tmp = path.with_name(f".{path.name[:NAME_ROOM]}.{secrets.token_hex(8)}.tmp")
        try:
            return os.open(tmp, flags, 0o666), tmp
        except FileExistsError:
            continue
    raise FileExistsError(errno.EEXIST, "no free name for a temporary file (100 tried)", str(path))


def _link_new(tmp, path):
    """Give the written temporary the name `path` only if nothing has it (FileExistsError
    otherwise): a hard link is atomic and never replaces."""
    try:
        os.link(tmp, path)
    except FileExistsError:
        raise FileExistsError(errno.EEXIST, "exists (not overwritten)", str(path)) from None
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV):
            raise
        os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o666))
        os.replace(tmp, path)           # a file system without hard links: the name reserved, then filled
        return
    os.unlink(tmp)


def _sync_folder(folder):
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return                           # Windows opens no folder; the rename is done
    try:
        os.fsync(fd)                     # the rename itself survives a power cut
    except OSError:
        pass
    finally:
        os.close(fd)


def name_problem(path, longest_suffix: int = 0) -> str | None:
    """Why a part of `path` is too long a file name (with `longest_suffix` characters a writer adds
    to its last part), or None."""
    path = Path(path)
    for part in path.parts:
        added = longest_suffix if part == path.name else 0
        if len(os.fsencode(part)) + added > NAME_MAX:
            return (f"the name {part[:40]}... is {len(part)} characters" + (f" (+{added} added)" if added else "")
                    + f"; a file name has at most {NAME_MAX}")
    return None


def output_problem(path, *, folder: bool = False, longest_suffix: int = 0) -> str | None:
    """Why `path` cannot be written as an output file (or, `folder=True`, made the output folder),
    said before any work, or None: a name too long (with `longest_suffix` characters the writer
    adds), a dangling link, a folder where a file goes or the reverse, or a nearest existing folder
    in which no file can be created (tried: a read-only mount, /proc, no permission)."""
    path = Path(path)
    problem = name_problem(path, longest_suffix)
    if problem:
        return problem
    if path.is_symlink() and not path.exists():
        return f"{path} is a symbolic link to nothing"
    if folder and path.exists() and not path.is_dir():
        return f"{path} is an existing file, not a folder"
    if not folder and path.is_dir():
        return f"{path} is a folder; give a file name"
    existing = next((p for p in (path if folder else path.parent, *path.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        return f"{existing} is a file, so {path if folder else path.parent} cannot be a folder"
    try:
        fd, probe = _create_temporary(existing / ".mechopt-probe")
    except OSError as exc:
        return f"no file can be created in {existing} ({exc.strerror})"
    os.close(fd)
    probe.unlink(missing_ok=True)
    return None


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


def read_regular(path, *, max_bytes: int, what: str, follow_links: bool = True) -> bytes:
    """The bytes of `path`, refused unless it is a regular file of at most `max_bytes` bytes read
    (`what` names it in the message: "a scene file")
    (not as `st_size` says: /dev/zero reports 0 and never ends; a FIFO would block forever).
    `follow_links=False` refuses a symbolic link (OSError ELOOP): for files only mechopt writes.
    Raises OSError (a missing or unreadable file) or ValueError naming `what` and the limit."""
    key = str(real_path(path))
    data = _SHIPPED.get().get(key)
    if data is None:
        with open_regular(path, max_bytes=max_bytes, what=what, follow_links=follow_links) as f:
            data = _read_bounded(f, path, max_bytes, what)
    for got in _RECORDERS.get():
        got[key] = data
    return data


def real_path(path) -> Path:
    """`path` with its symbolic links followed as far as they go. A loop of links is left for
    open() to refuse (ELOOP: one clear line), where Path.resolve raises RuntimeError (Python < 3.13)."""
    return Path(os.path.realpath(path))


@contextmanager
def open_regular(path, *, max_bytes: int, what: str, follow_links: bool = True):
    """`path` open for reading (a binary file object, for readers such as pyarrow that take one),
    refused as `read_regular` refuses: not a regular file, or larger than `max_bytes`."""
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    if not follow_links:
        flags |= getattr(os, "O_NOFOLLOW", 0)
    fd = os.open(path, flags)          # non-blocking: opening a FIFO with no writer returns at once
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = ("folder" if stat.S_ISDIR(mode) else "FIFO" if stat.S_ISFIFO(mode)
                    else "socket" if stat.S_ISSOCK(mode) else "device")
            raise ValueError(f"{path}: a {kind}, not {what} (references must name regular files)")
        size = os.fstat(fd).st_size
        if size > max_bytes:         # said before reading; read_regular counts too, should the file grow
            raise ValueError(f"{path}: {size / 1e6:.3g} MB; {what} is at most {max_bytes / 1e6:g} MB")
        f = os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
    with f:
        yield f


def _read_bounded(f, path, max_bytes, what):
    chunks, total = [], 0
    while chunk := f.read(min(1 << 20, max_bytes + 1 - total)):
        chunks.append(chunk)
        total += len(chunk)
        if total > max_bytes:
            raise ValueError(f"{path}: more than {max_bytes / 1e6:g} MB; {what} is at most {max_bytes / 1e6:g} MB")
    return b"".join(chunks)


def take_lock(path) -> int | None:
    """An open descriptor holding an exclusive lock on the file `path` (created if absent), or None
    when another process holds it. A symbolic link, folder, FIFO or device at `path` is refused
    (ValueError), never followed: a lock is written to, and a link would make it truncate its target.
    A file with other names (hard links) is refused too: writing a pid would change that file.
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
        found = os.fstat(fd)
        if not stat.S_ISREG(found.st_mode):
            raise ValueError(f"{path}: not a regular file (a FIFO, device or socket) where a lock file belongs; "
                             "remove it")
        if found.st_nlink > 1:         # another name of the same file: a lock is written to, that file is not ours
            raise ValueError(f"{path}: a file with {found.st_nlink - 1} other name(s) (a hard link) where a lock "
                             "file belongs; it is not written to: remove this name")
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

"""Writing files so that nothing is ever half-written: a temporary file `<name>.<pid>.tmp` beside
the target, flushed to disk, renamed over it, and the folder synced (a reader sees the old file or
the new one, even after a power cut; a sweep removes temporaries a killed writer left)."""
import os
from pathlib import Path


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

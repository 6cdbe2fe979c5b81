"""Writing files so that nothing is ever half-written: a temporary file beside the target,
flushed to disk, then renamed over it (a reader sees the old file or the new one)."""
import os
import tempfile
from pathlib import Path


def write_text_atomic(path, text: str) -> Path:
    """Write `text` to `path` atomically (parent folders created); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=path.parent, prefix=f".{path.name}.", suffix=".tmp",
                                     delete=False, encoding="utf-8") as tmp:
        try:
            tmp.write(text)
            tmp.flush()
            os.fsync(tmp.fileno())
        except BaseException:
            os.unlink(tmp.name)
            raise
    os.replace(tmp.name, path)
    return path

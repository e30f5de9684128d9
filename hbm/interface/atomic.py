"""Files written whole or not at all, and an output folder used by one run at a time.

``write_atomic`` writes to a temporary file of a unique name in the target's folder and
renames it over the target (``os.replace`` is atomic on one file system), so a reader never
sees half a file and two writers never share a temporary.  ``FolderLock`` holds
``OUTDIR/.hbm.lock`` (created exclusively, holding the owner's process id) while a sweep
writes into ``OUTDIR``: a second sweep into the same folder is refused in one line; a lock
left by a process that no longer runs (a killed sweep) is taken over.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

LOCK_NAME = ".hbm.lock"


def write_atomic(path: Path, text: str) -> None:
    """Replace ``path`` by ``text`` in one step (unique temporary in the same folder)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


class FolderLock:
    """Exclusive use of a folder by this process (context manager).

    Raises
    ------
    hbm.interface.case.CaseError
        When another running process holds the folder.
    """

    def __init__(self, folder: Path):
        self.path = Path(folder) / LOCK_NAME

    def __enter__(self):
        from hbm.interface.case import CaseError
        for _ in range(2):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                try:
                    owner = int(self.path.read_text().strip() or 0)
                except (OSError, ValueError):
                    owner = 0
                if owner and owner != os.getpid() and _alive(owner):
                    raise CaseError(f"output folder {str(self.path.parent)!r} is in use by another run "
                                    f"(process {owner}); choose another -o or wait for it") from None
                self.path.unlink(missing_ok=True)          # stale: its owner is gone
                continue
            with os.fdopen(fd, "w") as fh:
                fh.write(str(os.getpid()))
            return self
        raise CaseError(f"cannot lock output folder {str(self.path.parent)!r}")

    def __exit__(self, *exc):
        self.path.unlink(missing_ok=True)
        return False

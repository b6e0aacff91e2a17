"""Fault injection for tests/test_pipeline.py (on PYTHONPATH only for the interrupted run).

With VIDSTYLE_FAULT_DIR=<dir>, VIDSTYLE_FAULT_AFTER=<n> and VIDSTYLE_FAULT_SENTINEL=<file>, every Python process of the run (the vidstyle
command and its worker processes) publishes at most n ``.npz`` files into <dir> through
``vidstyle.fileio.atomic_path``'s rename: the writer of the next one, with its temporary file complete
but not yet renamed, creates <file> and blocks, as do all later writers. The test then
kills the run at exactly that point. Publishing is serialised by a lock file, so exactly n files are
published whatever the number of workers.
"""

import os

_DIR = os.environ.get("VIDSTYLE_FAULT_DIR")
if _DIR:
    import fcntl
    import time

    _AFTER = int(os.environ.get("VIDSTYLE_FAULT_AFTER", "1"))
    _SENTINEL = os.environ["VIDSTYLE_FAULT_SENTINEL"]
    _real_replace = os.replace

    def _replace(src, dst, *args, **kwargs):
        s, d = os.fspath(src), os.fspath(dst)
        base = os.path.basename(s)
        if (os.path.dirname(os.path.abspath(d)) == os.path.abspath(_DIR) and d.endswith(".npz")
                and base.startswith(".") and ".tmp" in base):
            lock = open(_SENTINEL + ".lock", "w")  # noqa: SIM115 (held until released or killed)
            fcntl.flock(lock, fcntl.LOCK_EX)  # held until the process dies when the fault is reached
            done = [f for f in os.listdir(_DIR) if f.endswith(".npz") and not f.startswith(".")]
            if len(done) >= _AFTER:
                with open(_SENTINEL, "w") as f:
                    f.write(f"{os.getpid()} {s}\n")
                while True:
                    time.sleep(60)
            try:
                return _real_replace(src, dst, *args, **kwargs)
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)
                lock.close()
        return _real_replace(src, dst, *args, **kwargs)

    os.replace = _replace

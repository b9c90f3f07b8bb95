"""A word while numba compiles bubblemesh's kernels (not in the paper).

Every kernel is compiled on its first call and kept in numba's on-disk cache
(``cache=True``), so the first mesh after an install, an upgrade or a cleared
cache waits a minute or two with nothing to show.  :func:`compile_notice`
says so once a process, on the first kernel that numba actually compiles: loading a
cached kernel fires no ``numba:compile`` event (numba's event API), so warm
runs stay silent.  The command line always listens; the library only with
``progress=True``.
"""

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import IO

_said = False  # once a process: bm.generate then bm.optimize compile in turn

NOTICE = ("bubblemesh: compiling its numba kernels; this happens once per install and takes "
          "a minute or two (numba caches them)")


@contextmanager
def compile_notice(stream: IO[str] | None = None) -> Iterator[None]:
    """Within the block, write NOTICE to ``stream`` (stderr by default) when the
    first bubblemesh kernel starts compiling; nothing if all come from the cache
    or numba is off (NUMBA_DISABLE_JIT)."""
    from numba.core import event

    class Notice(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            global _said
            dispatcher = (ev.data or {}).get("dispatcher")
            module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
            if not _said and module.split(".")[0] == "bubblemesh":
                _said = True
                print(NOTICE, file=stream if stream is not None else sys.stderr, flush=True)

        def on_end(self, ev: event.Event) -> None:
            pass

    with event.install_listener("numba:compile", Notice()):
        yield


@contextmanager
def maybe_notice(progress: bool) -> Iterator[None]:
    """:func:`compile_notice` where the caller asked for progress, else nothing."""
    if not progress:
        yield
        return
    with compile_notice():
        yield

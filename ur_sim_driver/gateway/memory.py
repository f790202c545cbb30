"""Handing memory back to the system after large trajectories (glibc; a no-op elsewhere).

A 100,000-point trajectory takes tens of MB while it runs. Two glibc behaviours would keep that memory in the
process after it is freed: the threshold above which blocks are mmap'ed rises by itself after a large block is
freed (so the next large numpy arrays come from the heap, which is not shrunk), and the hundreds of thousands
of small blocks of a deserialized message stay in the heap until it is trimmed. A trimmed heap keeps its free
space as address space, and the next large arrays of the same thread may be carved from it (the threshold only
applies when the heap has no free block large enough), so trimming follows every large trajectory, not only the
first. Fixing the threshold and trimming after a large trajectory give the memory back (measured in the intake
benchmark).
"""
from __future__ import annotations

import ctypes
import gc

_M_MMAP_THRESHOLD = -3  # mallopt parameter number in glibc's malloc.h
MMAP_THRESHOLD = 1 << 20  # [bytes] blocks from this size on are mmap'ed and returned to the system when freed


def _libc():
    try:
        libc = ctypes.CDLL('libc.so.6')
        return libc if hasattr(libc, 'mallopt') and hasattr(libc, 'malloc_trim') else None
    except OSError:
        return None


def use_mmap_for_large_blocks() -> bool:
    """Fix glibc's mmap threshold (call once per process). Returns False where there is no glibc."""
    libc = _libc()
    return bool(libc and libc.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD))


def release_memory() -> bool:
    """Collect garbage and trim the heap. Returns False where there is no glibc."""
    gc.collect()
    return trim_heap()


def trim_heap() -> bool:
    """Hand the free pages of every malloc arena back to the system (no garbage collection: for memory freed
    without cycles, such as a taken C message). Returns False where there is no glibc."""
    libc = _libc()
    return bool(libc and (libc.malloc_trim(0) or True))

//! [`SyncPtr`], a raw pointer that parallel writers may share.

// Unsafe: disjoint parallel writes through `SyncPtr` (each index written by one task), and unchecked indexing in the hot loop behind checked bounds; see the SAFETY comments.
#![allow(unsafe_code)]

/// A raw pointer into a buffer that several rayon tasks write to at the same time.
///
/// `*mut T` is neither `Send` nor `Sync`; this wrapper is both, so a closure run on several
/// threads can hold it. Constructing one is safe; every write through it is `unsafe` and
/// the writer must uphold the contract:
///
/// * **disjoint indices**: no element is written by more than one task, and no element a
///   task writes is read or written by another task (or through another reference) while
///   the parallel section runs;
/// * every written index lies within the buffer's allocation (its capacity), and the buffer
///   is neither moved, reallocated nor dropped until the parallel section has finished
///   (rayon's `for_each` returns only after all tasks have);
/// * elements written beyond the vector's length are only exposed (`set_len`, or read as
///   part of the length) once every one of them has been written.
///
/// Closures should copy the whole wrapper into a local (`let p = ptr;`) before using
/// `p.0`: with edition-2021 disjoint captures, naming `ptr.0` directly would capture only
/// the bare `*mut T`, which is not `Send`.
#[derive(Clone, Copy)]
pub(crate) struct SyncPtr<T>(pub(crate) *mut T);

// SAFETY: the pointer is only dereferenced under the contract above (disjoint writes while
// the buffer outlives the parallel section), which rules out data races between threads.
unsafe impl<T> Send for SyncPtr<T> {}
// SAFETY: as for `Send`; shared access only copies the pointer value.
unsafe impl<T> Sync for SyncPtr<T> {}

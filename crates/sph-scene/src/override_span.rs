//! The spans of values set by an override (`--set KEY=VALUE`, [`crate::Override`]): a
//! leaf module, so that the error messages (`error.rs`) and the overrides
//! (`overrides.rs`) both use it without importing each other.

/// The span given to the keys and values an override puts into the document: past the end
/// of any scene text ([`crate::MAX_SCENE_FILE_BYTES`]), so that messages can tell them from
/// the file's own ([`is_override_span`]).
const OVERRIDE_OFFSET: usize = usize::MAX / 2;

/// Whether a span of the document belongs to a value set by an override (not in the file).
pub(crate) fn is_override_span(start: usize) -> bool {
    start >= OVERRIDE_OFFSET
}

/// The span of a key or value an override sets.
pub(crate) fn override_span() -> std::ops::Range<usize> {
    OVERRIDE_OFFSET..OVERRIDE_OFFSET
}

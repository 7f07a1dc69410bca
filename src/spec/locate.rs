//! Positions of fields in pipeline text (placeholder until the span-aware locator lands).

/// 1-based (line, column) of the node at `path` in `text`, if found.
pub fn locate(_text: &str, _path: &[String]) -> Option<(usize, usize)> {
    None
}

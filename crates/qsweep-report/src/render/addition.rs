//! What a part of the report built above the generic one (the replication's Table III) adds to a
//! report folder: its own files, written before the generic ones, its data links, and its
//! sections of `index.html` and `README.md`. The generic folder ([`crate::render::folder`]) and
//! pages ([`crate::render::html`], [`crate::render::markdown`]) place what they are given without
//! knowing what it is, so they work for any pipeline.

/// A section of `index.html`: its anchor and title in the page's navigation, and its HTML.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Section {
    /// The anchor (`id`) of its heading.
    pub id: String,
    /// Its title in the navigation (already HTML).
    pub nav: String,
    /// The section, heading included (already HTML).
    pub html: String,
}

/// What is added to one report folder (see the module documentation); the default adds nothing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Addition {
    /// Files (name relative to the folder, bytes), written first, in this order.
    pub files: Vec<(String, Vec<u8>)>,
    /// `index.html`'s data links placed before the generic ones (already HTML).
    pub html_links: Vec<String>,
    /// `README.md`'s data links placed before the generic ones (already Markdown).
    pub md_links: Vec<String>,
    /// `index.html`'s sections, placed before the systems' sections.
    pub html_sections: Vec<Section>,
    /// `README.md`'s text placed after the counts, before the figures (already Markdown).
    pub markdown: String,
}

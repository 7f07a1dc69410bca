//! Escaping, one function per output format, so that each rule is defined once. Text a pipeline's
//! author wrote (its `description`, experiment and variant titles, ids and names, `set`
//! overrides, the pipeline's path) reaches every page and figure; written through these functions
//! it shows as the text it is and never becomes markup:
//!
//! - [`html`]: `index.html` (element content and attribute values);
//! - [`xml`]: the SVG figures' text (content and attribute values);
//! - [`markdown`] for prose, [`markdown_cell`] for a pipe table's cell and [`markdown_code`] for a
//!   code span: `README.md` and the `.md` tables;
//! - [`latex`] (text mode) and [`latex_comment`]: `table3.tex`.
//!
//! qsweep's own text (captions, rules, headings) is written as the format's source where it uses
//! the format (a caption's Markdown code spans); in a Markdown table it only needs
//! [`markdown_table_text`], which keeps the table's structure.

/// Text for HTML element content and attribute values (quoted with `"` or `'`): `&`, `<`, `>`,
/// `"` and `'` as character references.
pub fn html(s: &str) -> String {
    markup(s, "&#39;")
}

/// Text for SVG (XML) character data and attribute values: `&`, `<`, `>`, `"` and `'` as XML's
/// predefined entities.
pub fn xml(s: &str) -> String {
    markup(s, "&apos;")
}

/// `&`, `<`, `>` and `"` as entities, and `'` as `apos` (HTML and XML spell it differently).
fn markup(s: &str, apos: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str(apos),
            _ => out.push(c),
        }
    }
    out
}

/// Plain text as inline Markdown (CommonMark and GitHub's extensions), shown as written wherever
/// it is put: a paragraph, a heading, a list item, a link's text or an image's alt text.
///
/// - `&`, `<`, `>` become entities: no raw HTML, autolink, entity or block quote;
/// - `\`, `` ` ``, `[`, `]`, `*` and `~` are backslash-escaped: no code span, link, image,
///   emphasis or strikethrough, and no backslash that escapes the page's own syntax after it;
/// - `_` is escaped unless it stands between two letters or digits (`x_dot`), where it can
///   neither open nor close emphasis;
/// - a line break becomes a space (the text is one paragraph, as HTML shows it), so no block
///   (heading, list, table, reference definition) can start inside the text;
/// - a first character that would start a block at the start of a line (`#`, `-`, `+`, `=`, or
///   the `.`/`)` after leading digits) is escaped.
///
/// `|` is left as it is: it only matters inside a table ([`markdown_cell`]).
pub fn markdown(s: &str) -> String {
    markdown_text(s, true)
}

/// [`markdown`], with the escapes of a line's start only when `line_start` (inside a table cell no
/// block can start, so `0.1` needs no `0\.1` there).
fn markdown_text(s: &str, line_start: bool) -> String {
    let chars: Vec<char> = s.chars().map(|c| if c == '\n' || c == '\r' { ' ' } else { c }).collect();
    let digits = chars.iter().take_while(|c| c.is_ascii_digit()).count();
    let mut out = String::with_capacity(s.len() + 8);
    for (i, &c) in chars.iter().enumerate() {
        let word = |k: Option<usize>| k.and_then(|k| chars.get(k)).is_some_and(|c| c.is_alphanumeric());
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '\\' | '`' | '[' | ']' | '*' | '~' => {
                out.push('\\');
                out.push(c);
            }
            '_' if !(word(i.checked_sub(1)) && word(Some(i + 1))) => out.push_str("\\_"),
            '#' | '-' | '+' | '=' if i == 0 && line_start => {
                out.push('\\');
                out.push(c);
            }
            '.' | ')' if i == digits && digits > 0 && line_start => {
                out.push('\\');
                out.push(c);
            }
            _ => out.push(c),
        }
    }
    out
}

/// Plain text as one cell of a Markdown pipe table: [`markdown`], and `|` escaped so it does not
/// end the cell.
pub fn markdown_cell(s: &str) -> String {
    markdown(s).replace('|', "\\|")
}

/// [`markdown_cell`] without the escapes of a line's start, which a table cell does not need
/// (`0.1`, `-3` stay as they are); the program report's tables use it.
pub fn markdown_in_cell(s: &str) -> String {
    markdown_text(s, false).replace('|', "\\|")
}

/// qsweep's own text (which may use Markdown, such as a code span) in a Markdown table's caption,
/// heading or cell: only `|` is escaped and line breaks become spaces, which keeps the table whole.
pub fn markdown_table_text(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// Plain text as a Markdown code span, shown literally: fenced by one more backtick than its
/// longest run of backticks, padded with a space where it starts or ends with one, line breaks
/// as spaces (a code span shows backslashes and `<` as they are, so nothing else is escaped).
pub fn markdown_code(s: &str) -> String {
    let s = s.replace(['\n', '\r'], " ");
    let (mut longest, mut run) = (0, 0);
    for c in s.chars() {
        run = if c == '`' { run + 1 } else { 0 };
        longest = longest.max(run);
    }
    let fence = "`".repeat(longest + 1);
    let pad = if s.starts_with('`') || s.ends_with('`') { " " } else { "" };
    format!("{fence}{pad}{s}{pad}{fence}")
}

/// A symbol of the report's text as LaTeX math (without the `$`), where it has one.
fn latex_math(c: char) -> Option<&'static str> {
    Some(match c {
        'α' => "\\alpha",
        'γ' => "\\gamma",
        'ε' => "\\varepsilon",
        'θ' => "\\theta",
        'λ' => "\\lambda",
        'σ' => "\\sigma",
        'Δ' => "\\Delta",
        '±' => "\\pm",
        '×' => "\\times",
        '≥' => "\\geq",
        '≤' => "\\leq",
        '≈' => "\\approx",
        '−' => "-",
        '†' => "^\\dagger",
        _ => return None,
    })
}

/// Text for LaTeX's text mode: the specials `\ { } $ & # ^ _ % ~` (and `| < >`, which the
/// default font encoding prints as other glyphs) escaped; the report's Unicode symbols (λ, θ, ±,
/// a combining dot as in ẋ, …) as math and dashes as TeX ligatures, so pdflatex needs nothing
/// beyond `\usepackage{booktabs}`; a line break becomes a space.
pub fn latex(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        if chars.peek() == Some(&'\u{307}') {
            chars.next();
            let base = latex_math(c).map_or_else(|| c.to_string(), str::to_string);
            out.push_str(&format!("$\\dot{{{base}}}$"));
            continue;
        }
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            '|' => out.push_str("\\textbar{}"),
            '<' => out.push_str("\\textless{}"),
            '>' => out.push_str("\\textgreater{}"),
            '—' => out.push_str("---"),
            '–' => out.push_str("--"),
            '\n' | '\r' => out.push(' '),
            _ => match latex_math(c) {
                Some(m) => out.push_str(&format!("${m}$")),
                None => out.push(c),
            },
        }
    }
    out
}

/// Text for a LaTeX comment (`% …` to the end of the line): TeX ignores everything there but a
/// line break, which would end the comment, so line breaks become spaces.
pub fn latex_comment(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

#[cfg(test)]
mod tests {
    use super::*;

    const HOSTILE: &str = "<script>alert(1)</script> <img src=x onerror=alert(1)> \\input{/etc/passwd} \
                           $x$ 50% #1 _a_ [l](javascript:x) | p & 'q' \"r\" ~ ^ `c`";

    #[test]
    fn html_and_xml_escape_markup_and_both_quotes() {
        assert_eq!(
            html("<a href=\"x\" title='y'>&amp;</a>"),
            "&lt;a href=&quot;x&quot; title=&#39;y&#39;&gt;&amp;amp;&lt;/a&gt;"
        );
        assert_eq!(
            xml("<a href=\"x\" title='y'>&amp;</a>"),
            "&lt;a href=&quot;x&quot; title=&apos;y&apos;&gt;&amp;amp;&lt;/a&gt;"
        );
        assert_eq!(html("Q(λ) ± 2, ẋ"), "Q(λ) ± 2, ẋ");
        for out in [html(HOSTILE), xml(HOSTILE)] {
            assert!(!out.contains(['<', '>', '"', '\'']), "{out}");
            // Every `&` starts an entity.
            for (i, _) in out.match_indices('&') {
                let ent = &out[i..out[i..].find(';').map_or(out.len(), |e| i + e + 1)];
                assert!(["&amp;", "&lt;", "&gt;", "&quot;", "&#39;", "&apos;"].contains(&ent), "{ent}");
            }
        }
    }

    #[test]
    fn markdown_neutralises_html_and_inline_syntax() {
        assert_eq!(
            markdown("<script>alert(1)</script> & <img src=x onerror=alert(1)>"),
            "&lt;script&gt;alert(1)&lt;/script&gt; &amp; &lt;img src=x onerror=alert(1)&gt;"
        );
        assert_eq!(markdown("[l](javascript:x) ![i](y)"), "\\[l\\](javascript:x) !\\[i\\](y)");
        assert_eq!(markdown("`code` *em* ~s~ a\\b"), "\\`code\\` \\*em\\* \\~s\\~ a\\\\b");
        // Underscores: escaped where they could start or end emphasis, not inside a word.
        assert_eq!(markdown("_a_ x_dot q_init __b__"), "\\_a\\_ x_dot q_init \\_\\_b\\_\\_");
        // Blocks cannot start: a leading marker is escaped and line breaks become spaces.
        assert_eq!(markdown("# h"), "\\# h");
        assert_eq!(markdown("- item"), "\\- item");
        assert_eq!(markdown("12. item"), "12\\. item");
        assert_eq!(markdown("3) item"), "3\\) item");
        assert_eq!(markdown("a\n# b\n[x]: javascript:y"), "a # b \\[x\\]: javascript:y");
        // What qsweep's committed pipelines write stays as it is.
        for s in [
            "Bins + Actions",
            "gym-v0 tutorial with velocity ranges ±0.5 m/s, ±50°/s",
            "gym-v0-reset, Ball-Beam as ballbeam-gym: beam angle rate-controlled (±0.8 rad/s, |θ| ≤ 0.2)",
            "Full replication grid of \"Performance analysis\" (Tables I-III, Figures 5-7), 10 seeds.",
            "systems.ball-beam.ranges.x_dot = - -0.5 - 0.5, defaults.q_init = -1",
            "Gymnasium's random start states",
            "1 row",
        ] {
            assert_eq!(markdown(s), s);
        }
        // Nothing of the hostile text is left to parse as HTML or a link.
        let out = markdown(HOSTILE);
        assert!(!out.contains('<') && !out.replace("\\]", "").contains("]("), "{out}");
    }

    #[test]
    fn markdown_cells_also_escape_pipes() {
        assert_eq!(markdown_cell("a | b"), "a \\| b");
        assert_eq!(markdown_cell("<b>|</b>"), "&lt;b&gt;\\|&lt;/b&gt;");
        assert_eq!(markdown_table_text("`fresh:` a|b\nc"), "`fresh:` a\\|b c");
        assert_eq!(markdown_in_cell("0.1 | -3 [x]"), "0.1 \\| -3 \\[x\\]");
        assert_eq!(markdown_cell("0.1"), "0\\.1");
    }

    #[test]
    fn markdown_code_spans_show_any_text_literally() {
        assert_eq!(
            markdown_code("qsweep report p.yaml --variant 'v'"),
            "`qsweep report p.yaml --variant 'v'`"
        );
        assert_eq!(markdown_code("a`b"), "``a`b``");
        assert_eq!(markdown_code("``x"), "``` ``x ```");
        assert_eq!(markdown_code("a\nb"), "`a b`");
    }

    #[test]
    fn latex_escapes_every_special() {
        assert_eq!(
            latex("\\ { } $ & # ^ _ % ~"),
            "\\textbackslash{} \\{ \\} \\$ \\& \\# \\textasciicircum{} \\_ \\% \\textasciitilde{}"
        );
        assert_eq!(latex("\\input{/etc/passwd}"), "\\textbackslash{}input\\{/etc/passwd\\}");
        assert_eq!(latex("θ\u{307} & x\u{307}"), "$\\dot{\\theta}$ \\& $\\dot{x}$");
        assert_eq!(latex("x_dot 5% ~"), "x\\_dot 5\\% \\textasciitilde{}");
        assert_eq!(latex("a|b <c> — d – e\nf"), "a\\textbar{}b \\textless{}c\\textgreater{} --- d -- e f");
        assert_eq!(latex_comment("a\nb % c"), "a b % c");
    }
}

//! What a pipeline's author writes (its description, experiment and variant titles) reaches every
//! output, and must show there as the text it is: a report of a pipeline whose texts are hostile
//! markup in every format is checked file by file, each against an oracle written here
//! independently of `src/report/escape.rs`.

use crate::helpers::Sandbox;
use std::path::{Path, PathBuf};

/// Markup of every format the report writes.
const HOSTILE: &str =
    "<script>alert(1)</script> <img src=x onerror=alert(1)> \\input{/etc/passwd} $x$ 50% #1 \
                       _a_ [l](javascript:x) | p & q ~ ^ `c` \"d\" 'e'";

/// The description: the hostile text after a heading marker, then a list item and a link
/// reference definition on lines of their own.
fn description() -> String {
    format!("# {HOSTILE}\n- item\n[l]: javascript:y")
}

/// Mountain Car of `tests/fixtures/pipelines/variants.yaml`, one experiment (id `e_2`: `_` is a
/// LaTeX special) titled with the hostile text, and two variants titled with it.
fn pipeline() -> String {
    let q = |s: &str| serde_json::to_string(s).unwrap(); // a JSON string is a YAML double-quoted one
    format!(
        "name: hostile\n\
         description: {}\n\
         seeds: 2\n\
         defaults:\n  max_episodes: 30\n\
         systems:\n  mountain-car:\n\
         \x20   crisp: {{ epsilon: 0.05, gamma: 0.95, alpha: 0.01, lambda: 0.6 }}\n\
         \x20   fuzzy: {{ epsilon: 0.05, gamma: 0.95, alpha: 0.01, lambda: 0.6 }}\n\
         \x20   success: {{ within: 400, streak: 1, max_episode_steps: 2000 }}\n\
         \x20   experiments:\n\
         \x20     - id: e_2\n\
         \x20       title: {1}\n\
         \x20       repr: crisp\n\
         \x20       vary: {{ x == x_dot: [2, 4], actions: [2, 3] }}\n\
         \x20       reference:\n\
         \x20         q0: {{ mean: 20, std: 5, resolution: [2, 2], actions: 3 }}\n\
         \x20         q-lambda: {{ mean: 10, std: 3, resolution: [4, 4], actions: 2 }}\n\
         variants:\n\
         \x20 - id: base\n    title: {1}\n\
         \x20 - id: fast\n    title: {1}\n    set: {{ systems.mountain-car.crisp.alpha: 0.05 }}\n",
        q(&description()),
        q(HOSTILE)
    )
}

fn files(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, ext, out);
        } else if p.extension().is_some_and(|x| x == ext) {
            out.push(p);
        }
    }
    out.sort();
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The report of the hostile pipeline, every format (PNG figures too).
fn report() -> (Sandbox, PathBuf) {
    let sb = Sandbox::new();
    let p = sb.write("hostile.yaml", &pipeline());
    let out = sb.path("rep");
    let formats = "md,csv,tex,cells,svg,png,html";
    let args = ["run", p.to_str().unwrap(), "--quiet", "--formats", formats, "--out", out.to_str().unwrap()];
    sb.qsweep(&args).assert().success();
    (sb, out)
}

/// The start tags of an HTML page, as (lower-case name, attribute names) (an HTML tokenizer's
/// view, enough for pages whose only `<` are tags: escaped text has none).
fn html_tags(page: &str) -> Vec<(String, Vec<String>)> {
    let mut tags = Vec::new();
    let mut rest = page;
    while let Some(i) = rest.find('<') {
        rest = &rest[i + 1..];
        let name: String = rest.chars().take_while(|c| c.is_ascii_alphanumeric()).collect();
        let end = rest.find('>').expect("every tag closes");
        let inside = &rest[name.len()..end];
        let mut attrs = Vec::new();
        let mut s = inside.trim_start();
        while !s.is_empty() && s != "/" {
            let n: String = s.chars().take_while(|c| !c.is_whitespace() && *c != '=' && *c != '>').collect();
            s = &s[n.len()..];
            if let Some(v) = s.strip_prefix('=') {
                let (q, v) = (v.chars().next().unwrap(), &v[1..]);
                assert!(q == '"', "attribute {n} is double-quoted: {inside}");
                s = &v[v.find('"').unwrap() + 1..];
            }
            attrs.push(n.to_ascii_lowercase());
            s = s.trim_start();
        }
        if !name.is_empty() {
            tags.push((name.to_ascii_lowercase(), attrs));
        }
        rest = &rest[end..];
    }
    tags
}

/// HTML text with its character references decoded (those an HTML escape writes).
fn html_text(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&#39;", "'")
        .replace("&amp;", "&")
}

/// Inline Markdown text decoded: backslash escapes and the entities of `&`, `<`, `>`.
fn markdown_text(s: &str) -> String {
    let mut out = String::new();
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            let n = chars.next().expect("no trailing backslash");
            assert!(n.is_ascii_punctuation(), "only punctuation is escaped: \\{n}");
            out.push(n);
        } else {
            out.push(c);
        }
    }
    out.replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&")
}

/// The characters of `s` that are not backslash-escaped.
fn unescaped(s: &str) -> Vec<char> {
    let mut out = Vec::new();
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c == '\\' {
            chars.next();
        } else {
            out.push(c);
        }
    }
    out
}

/// Text in LaTeX's text mode, the specials escaped: the oracle for `table3.tex`.
fn latex_oracle(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '\\' => "\\textbackslash{}".to_string(),
            '~' => "\\textasciitilde{}".to_string(),
            '^' => "\\textasciicircum{}".to_string(),
            '{' | '}' | '$' | '&' | '#' | '_' | '%' => format!("\\{c}"),
            c => c.to_string(),
        })
        .collect()
}

/// Check a `table3.tex` line by line: every LaTeX special is escaped, or is qsweep's own markup
/// (the environments, rules and column separators, and math from a short list of symbols).
fn check_latex(tex: &str) {
    const WORDS: &[&str] = &[
        "begin",
        "end",
        "centering",
        "small",
        "caption",
        "toprule",
        "midrule",
        "bottomrule",
        "textbackslash",
        "textasciitilde",
        "textasciicircum",
        "textbar",
        "textless",
        "textgreater",
        "pm",
        "dagger",
        "dot",
        "lambda",
        "theta",
        "alpha",
        "gamma",
        "varepsilon",
        "sigma",
        "Delta",
        "times",
        "geq",
        "leq",
        "approx",
    ];
    assert!(tex.starts_with("% Table III"), "the comment line");
    let mut columns = None;
    let mut rows = 0;
    for line in tex.lines() {
        if line.starts_with("% Table III") {
            continue; // a comment to the end of the line (the name is a safe folder name)
        }
        if line.starts_with("\\begin{tabular}") {
            columns = None; // the next part of the table
        }
        let body = line.strip_suffix(" \\\\").unwrap_or(line);
        let mut math = false;
        let mut depth = 0i32;
        let mut seps = 0;
        let mut chars = body.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '\\' => {
                    let next = *chars.peek().unwrap_or_else(|| panic!("a lone backslash: {line}"));
                    if "&%$#_{}".contains(next) {
                        chars.next();
                        continue;
                    }
                    let word: String =
                        std::iter::from_fn(|| chars.next_if(|c| c.is_ascii_alphabetic())).collect();
                    assert!(WORDS.contains(&word.as_str()), "\\{word} is not qsweep's markup: {line}");
                }
                '$' => math = !math,
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    assert!(depth >= 0, "an unbalanced brace: {line}");
                }
                '_' | '^' => assert!(math, "a bare {c} outside math: {line}"),
                '%' | '#' | '~' => panic!("a bare {c}: {line}"),
                '&' => seps += 1,
                _ => {}
            }
        }
        assert!(!math && depth == 0, "math and braces close on their line: {line}");
        if seps > 0 {
            // Every row has the header's columns: no `&` of a text made a column.
            assert_eq!(seps, *columns.get_or_insert(seps), "{line}");
            rows += 1;
        }
    }
    assert!(rows > 0, "the table has rows");
}

#[test]
fn hostile_titles_and_descriptions_stay_text_in_every_output() {
    let (_sb, out) = report();
    let flat = |s: &str| s.replace('\n', " ");

    // index.html (the comparison's and each variant's): no script element, no event handler, and
    // the texts decode back to what the pipeline says.
    let mut pages = Vec::new();
    files(&out, "html", &mut pages);
    assert_eq!(pages.len(), 3, "{pages:?}");
    for p in &pages {
        let page = read(p);
        for (name, attrs) in html_tags(&page) {
            assert!(
                !["script", "iframe", "object", "embed"].contains(&name.as_str()),
                "{}: <{name}>",
                p.display()
            );
            assert!(attrs.iter().all(|a| !a.starts_with("on")), "{}: <{name} {attrs:?}>", p.display());
        }
        let d = page.split("<p>").nth(1).map(|s| &s[..s.find("</p>").unwrap()]).unwrap();
        assert_eq!(html_text(d), description(), "{}: the description, as text", p.display());
        assert!(page.contains("javascript:x"), "shown, as text");
        assert!(!page.contains("href=\"javascript"), "{}", p.display());
    }
    let variant = read(&out.join("fast/index.html"));
    assert!(html_text(&variant).contains(&format!("Exp. e_2: {HOSTILE}")), "the experiment's heading");
    assert!(html_text(&variant).contains(&format!("Variant fast: {HOSTILE} of pipeline hostile.")));

    // Every SVG parses, has no script and no event handler, and shows the titles as text.
    let mut svgs = Vec::new();
    files(&out, "svg", &mut svgs);
    assert!(svgs.len() >= 5, "{svgs:?}");
    for p in &svgs {
        let text = read(p);
        let doc = roxmltree::Document::parse(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        for n in doc.descendants().filter(|n| n.is_element()) {
            assert!(!n.has_tag_name("script") && !n.has_tag_name("foreignObject"), "{}", p.display());
            for a in n.attributes() {
                assert!(!a.name().to_ascii_lowercase().starts_with("on"), "{}: {}", p.display(), a.name());
            }
        }
        let name = p.file_name().unwrap().to_string_lossy();
        if name.starts_with("mountain-car") || name.starts_with("diff-") {
            let texts: Vec<&str> =
                doc.descendants().filter(|n| n.has_tag_name("text")).filter_map(|n| n.text()).collect();
            // (A title too long for its panel is shortened, so its start is compared.)
            assert!(
                texts.iter().any(|t| t.starts_with("Exp. e_2: <script>alert(1)</script>")),
                "{}: the panel title as text: {texts:?}",
                p.display()
            );
        }
    }

    // README.md: no raw HTML at all, no link or heading from the texts; they decode back.
    let mut mds = Vec::new();
    files(&out, "md", &mut mds);
    let readmes: Vec<&PathBuf> = mds.iter().filter(|p| p.ends_with("README.md")).collect();
    assert_eq!(readmes.len(), 3, "{mds:?}");
    for p in &readmes {
        let md = read(p);
        assert!(!md.contains('<'), "{}: raw HTML: {md}", p.display());
        let bare: String = unescaped(&md).into_iter().collect();
        assert!(!bare.contains("](javascript"), "{}: a link from the text", p.display());
        let headings: Vec<&str> = md.lines().filter(|l| l.starts_with('#')).collect();
        assert!(headings.iter().all(|h| h.starts_with("# qsweep") || h.starts_with("## ")), "{headings:?}");
        assert!(md.lines().all(|l| !l.starts_with("- item") && !l.starts_with("[l]:")), "{}", p.display());
        let d = md.lines().find(|l| l.starts_with("\\#")).unwrap_or_else(|| panic!("{}: {md}", p.display()));
        assert_eq!(markdown_text(d), flat(&description()), "{}: the description, as text", p.display());
        // `onerror=` only inside escaped text: every `<` is an entity.
        assert_eq!(md.matches("onerror=").count(), md.matches("&lt;img src=x onerror=").count());
    }
    let top = read(&out.join("README.md"));
    let item = top.lines().find(|l| l.starts_with("- ") && l.contains("`fast`")).unwrap();
    assert!(markdown_text(item).contains(&format!(": {HOSTILE} (")), "{item}");
    let note = read(&out.join("fast/README.md"));
    let note = note.lines().find(|l| l.starts_with("Variant fast")).unwrap();
    assert!(
        markdown_text(note).starts_with(&format!("Variant fast: {HOSTILE} of pipeline hostile.")),
        "{note}"
    );

    // variants.md: the title is one cell (its `|` escaped) and decodes back.
    let table = read(&out.join("variants.md"));
    let rows: Vec<&str> = table.lines().filter(|l| l.starts_with('|')).collect();
    let cells = |l: &str| unescaped(l).iter().filter(|&&c| c == '|').count();
    assert!(rows.iter().all(|r| cells(r) == cells(rows[0])), "{table}");
    let row = rows.iter().find(|r| r.contains("fast")).unwrap();
    assert!(markdown_text(row).contains(HOSTILE), "{row}");
    assert!(!row.contains('<'), "{row}");

    // table3.tex: every special escaped; the experiment id as the oracle escapes it.
    let mut texs = Vec::new();
    files(&out, "tex", &mut texs);
    assert_eq!(texs.len(), 2, "{texs:?}");
    for p in &texs {
        let tex = read(p);
        check_latex(&tex);
        assert!(tex.contains(&format!("Mountain Car & {} & Q(0)-learning", latex_oracle("e_2"))), "{tex}");
        for raw in ["\\input", "$x$ 50%", "#1", "_a_", "<script"] {
            assert!(!tex.contains(raw), "{}: {raw}", p.display());
        }
    }
}

#[test]
fn the_latex_oracle_escapes_every_special() {
    assert_eq!(
        latex_oracle("\\input{/etc/passwd} $x$ 50% #1 _a_ & ~ ^"),
        "\\textbackslash{}input\\{/etc/passwd\\} \\$x\\$ 50\\% \\#1 \\_a\\_ \\& \\textasciitilde{} \\textasciicircum{}"
    );
    // The escaped hostile text passes the file check; raw, each special fails it.
    let line = |s: &str| {
        format!("% Table III\n\\begin{{tabular}}{{ll}}\nh & h \\\\\na & {s} \\\\\n\\end{{tabular}}\n")
    };
    check_latex(&line(&latex_oracle(HOSTILE)));
    for raw in ["\\input{x}", "$x", "50%", "#1", "_a", "a & b", "~", "{"] {
        assert!(std::panic::catch_unwind(|| check_latex(&line(raw))).is_err(), "{raw}");
    }
}

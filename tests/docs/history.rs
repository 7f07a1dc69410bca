//! A guide a user reads, not a diary: README.md and the guide's pages hold no issue reference
//! (`#37`, "issue 37"), no commit hash and no date in their prose. What changed when belongs in
//! CHANGELOG.md. Code blocks and inline code are not prose (keys and digests in console examples
//! are fine), and the pre-registration is exempt: its dated declarations are the evidence.

use crate::markdown::{guide_docs, prose_lines};
use std::path::Path;

/// Pages where dates are the point.
const EXEMPT: [&str; 1] = ["docs/preregistration.md"];

/// README.md and every page under docs/, less [`EXEMPT`].
fn checked(path: &Path) -> bool {
    let p = path.to_string_lossy();
    (p == "README.md" || p.starts_with("docs/")) && !EXEMPT.contains(&p.as_ref())
}

/// The line with its inline code spans (`…`) blanked, so that only prose is searched.
fn without_inline_code(line: &str) -> String {
    let mut in_code = false;
    line.chars()
        .map(|c| {
            if c == '`' {
                in_code = !in_code;
                ' '
            } else if in_code {
                ' '
            } else {
                c
            }
        })
        .collect()
}

/// What the prose `line` holds of history: each issue reference, commit hash and date, described.
fn history_in(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let chars: Vec<char> = line.chars().collect();
    let digits_from = |i: usize| chars[i..].iter().take_while(|c| c.is_ascii_digit()).count();
    let word = |c: Option<&char>| c.is_some_and(|c| c.is_alphanumeric() || *c == '_');
    // The end of the last "issue N" found, so that its `#N` is not reported again.
    let mut covered = 0;
    for (i, &c) in chars.iter().enumerate() {
        // `#37`, not an anchor (`#3-steps`), an HTML entity (`&#8212;`) or a word's tail.
        if c == '#' && i >= covered {
            let n = digits_from(i + 1);
            let before = i.checked_sub(1).and_then(|j| chars.get(j));
            let after = chars.get(i + 1 + n);
            if n > 0 && !word(before) && before != Some(&'&') && !word(after) && after != Some(&'-') {
                out.push(format!("issue reference `{}`", chars[i..=i + n].iter().collect::<String>()));
            }
        }
        // "issue 37", "Issues #2", … at the start of a word.
        let issue = chars[i..].iter().take(5).flat_map(|c| c.to_lowercase()).eq("issue".chars());
        if issue && !word(i.checked_sub(1).and_then(|j| chars.get(j))) {
            let mut j = i + 5;
            if chars.get(j) == Some(&'s') {
                j += 1;
            }
            let spaces = chars[j..].iter().take_while(|c| c.is_whitespace()).count();
            j += spaces;
            if chars.get(j) == Some(&'#') {
                j += 1;
            }
            if spaces > 0 && digits_from(j) > 0 {
                let n = digits_from(j);
                covered = j + n;
                out.push(format!("issue reference `{}`", chars[i..j + n].iter().collect::<String>()));
            }
        }
        // A date, YYYY-MM-DD, not inside a longer number.
        let date = chars.get(i..i + 10).filter(|d| {
            let shape =
                d.iter()
                    .enumerate()
                    .all(|(k, c)| if k == 4 || k == 7 { *c == '-' } else { c.is_ascii_digit() });
            let edges = [i.checked_sub(1).and_then(|j| chars.get(j)), chars.get(i + 10)];
            shape && !edges.iter().any(|c| c.is_some_and(char::is_ascii_digit))
        });
        if let Some(d) = date {
            let two = |k: usize| d[k].to_digit(10).unwrap() * 10 + d[k + 1].to_digit(10).unwrap();
            if (1..=12).contains(&two(5)) && (1..=31).contains(&two(8)) {
                out.push(format!("date `{}`", d.iter().collect::<String>()));
            }
        }
    }
    // A commit hash: a word of 7 to 40 lowercase hex digits with both a digit and a letter (so
    // neither a number nor an English word such as "defaced").
    for w in line.split(|c: char| !c.is_ascii_alphanumeric()) {
        let hex = w.chars().all(|c| c.is_ascii_digit() || ('a'..='f').contains(&c));
        if (7..=40).contains(&w.len())
            && hex
            && w.chars().any(|c| c.is_ascii_digit())
            && w.chars().any(|c| c.is_ascii_alphabetic())
        {
            out.push(format!("commit hash `{w}`"));
        }
    }
    out
}

#[test]
fn the_guide_holds_no_issue_numbers_commit_hashes_or_dates() {
    let mut found = Vec::new();
    for doc in guide_docs().into_iter().filter(|d| checked(&d.path)) {
        for (i, line) in prose_lines(&doc.text).iter().enumerate() {
            for what in history_in(&without_inline_code(line)) {
                found.push(format!("{}:{}: {what}", doc.path.display(), i + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "history in the guide (it belongs in CHANGELOG.md; console examples and inline code may hold keys and digests):\n{}",
        found.join("\n")
    );
}

#[test]
fn history_is_found_in_prose_and_only_there() {
    let hits = |s: &str| history_in(&without_inline_code(s));
    for line in [
        "issue #27's ≤ 5 s is missed",
        "see issue 37",
        "Issues 2 and 3",
        "(#40, pre-registered)",
        "the build before (d2c5a34)",
        "measured on 2026-12-04, 2 cores",
        "commit 9f534f4.",
    ] {
        assert_eq!(hits(line).len(), 1, "{line}: {:?}", hits(line));
    }
    for line in [
        "see [Racing](racing.md#3-rounds) and &#8212; there",
        "the key `d2c5a34e9f` in code",
        "1,000,000 steps, 1234567 trials, seeds 1000..1019",
        "an effaced, defaced decade",
        "the tissue 3 layers",
        "blake3 of 2^20 rows, 0.80-1.25",
        "12026-12-041",
        "2026-13-04",
    ] {
        assert!(hits(line).is_empty(), "{line}: {:?}", hits(line));
    }
}

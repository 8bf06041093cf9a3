//! Rust source as the house tests read it (`layering.rs`, `size.rs`): the code alone, with
//! comments, strings and character literals blanked and line breaks kept, and the `#[cfg(test)]`
//! items found by their real extent.

#![allow(dead_code)] // each test uses what it needs of it

/// The code of `source` without its comments, strings and character literals (see
/// [`blank_non_code`]) and without its `#[cfg(test)]` items: what production code uses.
pub fn production_code(source: &str) -> String {
    let code = blank_non_code(source);
    let mut out = String::with_capacity(code.len());
    let mut from = 0;
    for (start, end) in test_ranges(&code) {
        out.push_str(&code[from..start]);
        from = end;
    }
    out.push_str(&code[from..]);
    out
}

/// The source with comments, string contents and character literals replaced by spaces, line
/// breaks kept, so that every brace, `fn` and attribute left is code. Rust's raw strings
/// (`r#"…"#`), byte strings and nested block comments are understood; a `'` that does not close
/// within a character is a lifetime or a label and stays.
pub fn blank_non_code(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let mut out: Vec<char> = chars.clone();
    let blank = |out: &mut Vec<char>, from: usize, to: usize| {
        for c in &mut out[from..to.min(chars.len())] {
            if *c != '\n' {
                *c = ' ';
            }
        }
    };
    let mut i = 0;
    while i < chars.len() {
        let next = chars.get(i + 1).copied();
        let literal = match chars[i] {
            '/' if next == Some('/') => {
                Some(chars[i..].iter().position(|&c| c == '\n').map_or(chars.len(), |n| i + n))
            }
            '/' if next == Some('*') => Some(block_comment_end(&chars, i)),
            '"' => Some(string_end(&chars, i + 1)),
            'r' | 'b' if starts_raw_string(&chars, i) => Some(raw_string_end(&chars, i)),
            '\'' => char_literal_end(&chars, i),
            c if c.is_alphanumeric() || c == '_' => {
                // A whole identifier, so that an `r` or a `b` ending one never starts a literal.
                i += chars[i..].iter().take_while(|&&c| c.is_alphanumeric() || c == '_').count();
                continue;
            }
            _ => None,
        };
        match literal {
            Some(end) => {
                blank(&mut out, i, end);
                i = end;
            }
            None => i += 1,
        }
    }
    out.into_iter().collect()
}

/// The end (one past the `*/`) of the block comment at `start`, nested ones included.
fn block_comment_end(chars: &[char], start: usize) -> usize {
    let (mut depth, mut i) = (0usize, start);
    while i + 1 < chars.len() {
        if chars[i] == '/' && chars[i + 1] == '*' {
            depth += 1;
            i += 2;
        } else if chars[i] == '*' && chars[i + 1] == '/' {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return i;
            }
        } else {
            i += 1;
        }
    }
    chars.len()
}

/// The end (one past the closing quote) of the string whose contents start at `from`.
fn string_end(chars: &[char], from: usize) -> usize {
    let mut i = from;
    while i < chars.len() {
        match chars[i] {
            '\\' => i += 2,
            '"' => return i + 1,
            _ => i += 1,
        }
    }
    chars.len()
}

/// Whether a raw string (`r"`, `r#"`, `br"`, `br#"`) or a byte string (`b"`) starts at `i`.
fn starts_raw_string(chars: &[char], i: usize) -> bool {
    let mut j = i;
    if chars[j] == 'b' {
        j += 1;
        if chars.get(j) == Some(&'"') {
            return true;
        }
    }
    if chars.get(j) != Some(&'r') {
        return false;
    }
    j += 1;
    while chars.get(j) == Some(&'#') {
        j += 1;
    }
    chars.get(j) == Some(&'"')
}

/// The end of the raw or byte string at `i` (which `starts_raw_string`).
fn raw_string_end(chars: &[char], i: usize) -> usize {
    let mut j = i + usize::from(chars[i] == 'b');
    if chars[j] == '"' {
        return string_end(chars, j + 1);
    }
    j += 1;
    let hashes = chars[j..].iter().take_while(|&&c| c == '#').count();
    let mut k = j + hashes + 1;
    while k < chars.len() {
        if chars[k] == '"' && chars[k + 1..].iter().take(hashes).filter(|&&c| c == '#').count() == hashes {
            return k + 1 + hashes;
        }
        k += 1;
    }
    chars.len()
}

/// The end of the character literal at `i` (`'x'`, `'\n'`, `'\u{7f}'`), or None for a lifetime.
fn char_literal_end(chars: &[char], i: usize) -> Option<usize> {
    match chars.get(i + 1)? {
        '\\' => {
            // The escaped character, then up to `u{10FFFF}` before the closing quote.
            let close = chars.get(i + 3..)?.iter().take(10).position(|&c| c == '\'')?;
            Some(i + 3 + close + 1)
        }
        '\n' => None,
        _ => (chars.get(i + 2) == Some(&'\'')).then_some(i + 3),
    }
}

/// The byte offset one past the brace that closes the one at `open`.
fn closing_brace(code: &str, open: usize) -> usize {
    let mut depth = 0usize;
    for (i, c) in code[open..].char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return open + i + 1;
                }
            }
            _ => {}
        }
    }
    code.len()
}

/// The end of the item that starts at `from`: its `;`, or the brace that closes its body.
/// Parentheses and brackets are skipped, so a `;` in `[u8; 4]` ends nothing.
pub fn item_end(code: &str, from: usize) -> Option<(usize, bool)> {
    let mut depth = 0usize;
    for (i, c) in code[from..].char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth = depth.saturating_sub(1),
            ';' if depth == 0 => return Some((from + i + 1, false)),
            '{' if depth == 0 => return Some((closing_brace(code, from + i), true)),
            _ => {}
        }
    }
    None
}

/// The byte ranges of `#[cfg(test)]` items (the attribute to the item's end).
pub fn test_ranges(code: &str) -> Vec<(usize, usize)> {
    let mut ranges = Vec::new();
    let mut from = 0;
    while let Some(at) = code[from..].find("#[cfg(test)]").map(|at| from + at) {
        let after = at + "#[cfg(test)]".len();
        let end = item_end(code, after).map_or(code.len(), |(end, _)| end);
        ranges.push((at, end));
        from = end;
    }
    ranges
}

//! A Rust lexer just good enough for the module graph and the function-length check:
//! identifiers and punctuation with their line numbers; comments, strings, character and
//! number literals dropped (a lifetime is kept as `'` + identifier, which nothing reads).

/// One token: an identifier or keyword, or a punctuation mark (`::` is one token).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Tok {
    Ident(String),
    Punct(&'static str),
}

/// A token and the 1-based line it starts on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Token {
    pub tok: Tok,
    pub line: usize,
}

impl Token {
    pub fn is(&self, p: &str) -> bool {
        matches!(&self.tok, Tok::Punct(q) if *q == p)
    }

    pub fn ident(&self) -> Option<&str> {
        match &self.tok {
            Tok::Ident(s) => Some(s),
            Tok::Punct(_) => None,
        }
    }

    pub fn is_ident(&self, word: &str) -> bool {
        self.ident() == Some(word)
    }
}

const PUNCTS: &[&str] = &[
    "::", "{", "}", "(", ")", "[", "]", ";", ",", "#", "!", "*", "<", ">", "=", ":", "&", "'", ".",
    "-", "+", "/", "|", "^", "%", "?", "@", "$", "~",
];

/// The tokens of `src`.
pub fn lex(src: &str) -> Vec<Token> {
    let b = src.as_bytes();
    let mut out = Vec::new();
    let (mut i, mut line) = (0usize, 1usize);
    while i < b.len() {
        let c = b[i];
        let start_line = line;
        if c == b'\n' {
            line += 1;
            i += 1;
        } else if c.is_ascii_whitespace() {
            i += 1;
        } else if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            i = block_comment(b, i, &mut line);
        } else if let Some(end) = raw_string(b, i) {
            line += count_lines(&b[i..end]);
            i = end;
        } else if c == b'"' || (c == b'b' && b.get(i + 1) == Some(&b'"')) {
            let open = if c == b'"' { i } else { i + 1 };
            i = quoted(b, open, b'"', &mut line);
        } else if c == b'\'' || (c == b'b' && b.get(i + 1) == Some(&b'\'')) {
            let open = if c == b'\'' { i } else { i + 1 };
            match char_literal(b, open) {
                Some(end) => i = end,
                None => {
                    out.push(punct("'", start_line));
                    i = open + 1;
                }
            }
        } else if c.is_ascii_digit() {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
                // A decimal point followed by a digit stays in the number.
                if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
                    i += 1;
                }
            }
        } else if c == b'_' || c.is_ascii_alphabetic() || c >= 0x80 {
            let start = if b[i..].starts_with(b"r#") { i + 2 } else { i };
            let mut end = start;
            while end < b.len()
                && (b[end] == b'_' || b[end].is_ascii_alphanumeric() || b[end] >= 0x80)
            {
                end += 1;
            }
            let word = String::from_utf8_lossy(&b[start..end]).into_owned();
            out.push(Token {
                tok: Tok::Ident(word),
                line: start_line,
            });
            i = end.max(i + 1);
        } else {
            let p = PUNCTS
                .iter()
                .find(|p| b[i..].starts_with(p.as_bytes()))
                .copied()
                .unwrap_or("?");
            out.push(punct(p, start_line));
            i += p.len().max(1);
        }
    }
    out
}

fn punct(p: &'static str, line: usize) -> Token {
    Token {
        tok: Tok::Punct(p),
        line,
    }
}

fn count_lines(b: &[u8]) -> usize {
    b.iter().filter(|&&c| c == b'\n').count()
}

/// The end of a (nested) block comment starting at `i`.
fn block_comment(b: &[u8], mut i: usize, line: &mut usize) -> usize {
    let mut depth = 0;
    while i < b.len() {
        if b[i..].starts_with(b"/*") {
            depth += 1;
            i += 2;
        } else if b[i..].starts_with(b"*/") {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return i;
            }
        } else {
            if b[i] == b'\n' {
                *line += 1;
            }
            i += 1;
        }
    }
    i
}

/// The end of a raw string (`r"…"`, `r#"…"#`, `br#"…"#`) starting at `i`, if one does.
fn raw_string(b: &[u8], i: usize) -> Option<usize> {
    let mut j = i;
    if b.get(j) == Some(&b'b') {
        j += 1;
    }
    if b.get(j) != Some(&b'r') {
        return None;
    }
    // Not the tail of an identifier such as `for` or `bar`.
    if i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_') {
        return None;
    }
    j += 1;
    let hashes = b[j..].iter().take_while(|&&c| c == b'#').count();
    j += hashes;
    if b.get(j) != Some(&b'"') {
        return None;
    }
    j += 1;
    let mut close = vec![b'"'];
    close.extend(std::iter::repeat_n(b'#', hashes));
    while j < b.len() {
        if b[j..].starts_with(&close) {
            return Some(j + close.len());
        }
        j += 1;
    }
    Some(b.len())
}

/// The end of a string quoted by `q` opening at `open`, escapes honoured.
fn quoted(b: &[u8], open: usize, q: u8, line: &mut usize) -> usize {
    let mut i = open + 1;
    while i < b.len() {
        match b[i] {
            b'\\' => i += 2,
            c if c == q => return i + 1,
            b'\n' => {
                *line += 1;
                i += 1;
            }
            _ => i += 1,
        }
    }
    i
}

/// The end of a character literal opening at `open`, or `None` for a lifetime or label.
fn char_literal(b: &[u8], open: usize) -> Option<usize> {
    let next = *b.get(open + 1)?;
    if next == b'\\' {
        let close = b[open + 2..].iter().position(|&c| c == b'\'')?;
        return Some(open + 2 + close + 1);
    }
    // One character (possibly multi-byte UTF-8) followed by the closing quote.
    let width = match next {
        c if c < 0x80 => 1,
        c if c >= 0xf0 => 4,
        c if c >= 0xe0 => 3,
        _ => 2,
    };
    (b.get(open + 1 + width) == Some(&b'\'')).then_some(open + 2 + width)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(src: &str) -> Vec<String> {
        lex(src)
            .into_iter()
            .map(|t| match t.tok {
                Tok::Ident(s) => s,
                Tok::Punct(p) => p.to_string(),
            })
            .collect()
    }

    #[test]
    fn comments_strings_and_chars_are_dropped() {
        let src = "use a::b; // use c::d\n/* x /* y */ z */ let s = \"q::r\"; let ch = '{';\n\
                   let r = r#\"}\"#; fn f<'a>(x: &'a u8) {}";
        let w = words(src);
        assert!(!w.iter().any(|x| x == "c" || x == "q" || x == "z"));
        assert_eq!(w.iter().filter(|x| *x == "{").count(), 1);
        assert!(w.contains(&"a".to_string()));
    }

    #[test]
    fn lines_are_counted_through_comments_and_strings() {
        let toks = lex("a\n/* b\n c */ \"d\ne\" f\n g");
        let lines: Vec<usize> = toks.iter().map(|t| t.line).collect();
        assert_eq!(lines, vec![1, 4, 5]);
    }
}

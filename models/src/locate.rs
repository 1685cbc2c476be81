//! Finding elements and fields in RON source text, so that errors found after
//! deserialization (unknown identifiers, bad masses…) carry a line and column.
//! A small tokenizer that skips whitespace, `//` and `/* */` comments and strings.

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    Str(String),
    Punct(char),
    Other,
}

/// The tokens of a RON text with their byte offsets and the matching
/// brackets of every group: positions of keys, strings and elements.
#[derive(Debug)]
pub struct Locator<'a> {
    src: &'a str,
    toks: Vec<(Tok, usize)>,
    /// For an opening bracket token, the index of its closing token.
    close: Vec<Option<usize>>,
}

/// A token range `[open, close]` of a bracketed group.
pub type Span = (usize, usize);

impl<'a> Locator<'a> {
    /// Tokenizes `src`.
    pub fn new(src: &'a str) -> Self {
        let bytes = src.as_bytes();
        let mut toks = Vec::new();
        let mut i = 0;
        while i < bytes.len() {
            let c = bytes[i];
            if c.is_ascii_whitespace() {
                i += 1;
            } else if bytes[i..].starts_with(b"//") {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            } else if bytes[i..].starts_with(b"/*") {
                i += 2;
                // Bytes, not chars: the comment may hold multi-byte characters.
                while i < bytes.len() && !bytes[i..].starts_with(b"*/") {
                    i += 1;
                }
                i = (i + 2).min(bytes.len());
            } else if c == b'"' {
                let start = i;
                i += 1;
                let mut s = String::new();
                while i < bytes.len() && bytes[i] != b'"' {
                    if bytes[i] == b'\\' && i + 1 < bytes.len() {
                        i += 1;
                    }
                    let ch = src[i..].chars().next().unwrap_or(' ');
                    s.push(ch);
                    i += ch.len_utf8();
                }
                i += 1;
                toks.push((Tok::Str(s), start));
            } else if c.is_ascii_alphabetic() || c == b'_' {
                let start = i;
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                toks.push((Tok::Ident(src[start..i].to_string()), start));
            } else if b"()[]{}:,".contains(&c) {
                toks.push((Tok::Punct(c as char), i));
                i += 1;
            } else {
                let start = i;
                let ch = src[i..].chars().next().unwrap_or(' ');
                i += ch.len_utf8().max(1);
                toks.push((Tok::Other, start));
            }
        }
        let mut close = vec![None; toks.len()];
        let mut stack = Vec::new();
        for (k, (t, _)) in toks.iter().enumerate() {
            match t {
                Tok::Punct('(' | '[' | '{') => stack.push(k),
                Tok::Punct(')' | ']' | '}') => {
                    if let Some(open) = stack.pop() {
                        close[open] = Some(k);
                    }
                }
                _ => {}
            }
        }
        Locator { src, toks, close }
    }

    /// 1-based (line, column in characters) of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        let offset = offset.min(self.src.len());
        let before = &self.src[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |p| p + 1);
        (line, before[line_start..].chars().count() + 1)
    }

    /// Byte offset of a 1-based (line, column) position.
    pub fn offset_of(&self, line: usize, col: usize) -> usize {
        let mut off = 0;
        for (k, l) in self.src.split_inclusive('\n').enumerate() {
            if k + 1 == line {
                return off
                    + l.char_indices()
                        .nth(col.saturating_sub(1))
                        .map_or(l.len(), |(b, _)| b);
            }
            off += l.len();
        }
        self.src.len()
    }

    fn is_key(&self, k: usize, key: &str) -> bool {
        matches!(&self.toks[k].0, Tok::Ident(s) if s == key)
            && matches!(self.toks.get(k + 1), Some((Tok::Punct(':'), _)))
    }

    /// Tokens directly inside a group (depth 1), as indices.
    pub fn children(&self, span: Span) -> Vec<usize> {
        let mut out = Vec::new();
        let mut k = span.0 + 1;
        while k < span.1 {
            out.push(k);
            k = match self.close[k] {
                Some(c) => c + 1,
                None => k + 1,
            };
        }
        out
    }

    /// The group following the key `key:` directly inside `span`.
    pub fn field_group(&self, span: Span, key: &str) -> Option<Span> {
        let kids = self.children(span);
        let k = kids.iter().copied().find(|&k| self.is_key(k, key))?;
        let mut v = k + 2;
        // Skip a constructor name such as `Diag(` or `Some(`.
        if matches!(self.toks.get(v), Some((Tok::Ident(_), _))) {
            v += 1;
        }
        Some((v, self.close.get(v).copied().flatten()?))
    }

    /// The whole file as a span: the top-level group (after an optional `Model`).
    pub fn top(&self) -> Option<Span> {
        let k = self
            .toks
            .iter()
            .position(|(t, _)| matches!(t, Tok::Punct('(' | '{')))?;
        Some((k, self.close[k]?))
    }

    /// The `nth` element `Ctor(… name: "name" …)` with `Ctor` one of `ctors`.
    pub fn element(&self, ctors: &[&str], name: &str, nth: usize) -> Option<Span> {
        (0..self.toks.len().saturating_sub(1))
            .filter_map(|k| {
                let Tok::Ident(c) = &self.toks[k].0 else {
                    return None;
                };
                if !ctors.contains(&c.as_str()) || self.toks[k + 1].0 != Tok::Punct('(') {
                    return None;
                }
                let span = (k + 1, self.close[k + 1]?);
                let found = self.children(span).into_iter().any(|j| {
                    self.is_key(j, "name")
                        && matches!(self.toks.get(j + 2), Some((Tok::Str(s), _)) if s == name)
                });
                found.then_some(span)
            })
            .nth(nth)
    }

    /// The `nth` key string `"name":` directly inside the map group `span`.
    pub fn map_entry(&self, span: Span, name: &str, nth: usize) -> Option<usize> {
        self.children(span)
            .into_iter()
            .filter(|&k| {
                matches!(&self.toks[k].0, Tok::Str(s) if s == name)
                    && matches!(self.toks.get(k + 1), Some((Tok::Punct(':'), _)))
            })
            .nth(nth)
    }

    /// The group opening at token `k`.
    pub fn group_after(&self, k: usize) -> Option<Span> {
        Some((k, self.close.get(k).copied().flatten()?))
    }

    /// The first `key:` anywhere inside `span`.
    pub fn key_anywhere(&self, span: Span, key: &str) -> Option<usize> {
        (span.0..span.1.min(self.toks.len())).find(|&k| self.is_key(k, key))
    }

    /// The first string literal with exactly this content inside `span`.
    pub fn string_in(&self, span: Span, text: &str) -> Option<usize> {
        (span.0..span.1.min(self.toks.len()))
            .find(|&k| matches!(&self.toks[k].0, Tok::Str(s) if s == text))
    }

    /// The constructor token before a group (the element's start), or the group itself.
    pub fn start_of(&self, span: Span) -> usize {
        if span.0 > 0 && matches!(self.toks[span.0 - 1].0, Tok::Ident(_)) {
            span.0 - 1
        } else {
            span.0
        }
    }

    /// Line and column of a token.
    pub fn pos(&self, tok: usize) -> (usize, usize) {
        self.line_col(self.toks.get(tok).map_or(self.src.len(), |t| t.1))
    }

    /// The innermost element (a constructor group with a `name: "…"`) containing
    /// the byte offset: its constructor and name.
    pub fn enclosing_named(&self, offset: usize) -> Option<(String, String)> {
        let mut best: Option<(usize, String, String)> = None;
        for k in 1..self.toks.len() {
            let (Tok::Punct('('), start) = &self.toks[k] else {
                continue;
            };
            let Some(c) = self.close[k] else { continue };
            let end = self.toks[c].1;
            if !(*start <= offset && offset <= end) {
                continue;
            }
            let Tok::Ident(ctor) = &self.toks[k - 1].0 else {
                continue;
            };
            let name = self.children((k, c)).into_iter().find_map(|j| {
                if self.is_key(j, "name") {
                    match self.toks.get(j + 2) {
                        Some((Tok::Str(s), _)) => Some(s.clone()),
                        _ => None,
                    }
                } else {
                    None
                }
            });
            if let Some(name) = name
                && best.as_ref().is_none_or(|b| *start >= b.0)
            {
                best = Some((*start, ctor.clone(), name));
            }
        }
        best.map(|(_, c, n)| (c, n))
    }
}

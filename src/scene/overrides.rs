//! `--set key.path=value`: edits the scene's RON text before it is parsed.
//!
//! Editing the text (rather than a generic value tree) keeps enum and struct names, which
//! `ron::Value` drops, and sends the result through the very same parser and checks as the
//! file itself. A small scanner finds the span of the value at a path; a field the file
//! leaves to its default is inserted into the enclosing struct.

/// A scanned RON value: its byte span and, for compound values, its parts.
#[derive(Debug)]
struct Node {
    start: usize,
    end: usize,
    kind: Kind,
}

#[derive(Debug)]
enum Kind {
    /// `Name(field: value, ..)` or `(field: value, ..)`; `close` is the offset of `)`.
    Struct {
        fields: Vec<(String, Node)>,
        close: usize,
    },
    /// `[a, b]`, `(a, b)` or `Name(a, b)`.
    Seq(Vec<Node>),
    /// Numbers, strings, identifiers, maps.
    Atom,
}

struct Scanner<'a> {
    s: &'a [u8],
    i: usize,
    /// Nesting depth, bounded so that no text can exhaust the stack.
    depth: usize,
}

/// Deeper nesting than any scene needs (RON's own parser stops at a similar depth).
const MAX_DEPTH: usize = 100;

impl<'a> Scanner<'a> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn fail<T>(&self, what: &str) -> Result<T, String> {
        Err(format!(
            "cannot read the scene near byte {}: {what}",
            self.i
        ))
    }

    fn skip_ws(&mut self) {
        loop {
            match (self.peek(), self.s.get(self.i + 1).copied()) {
                (Some(c), _) if c.is_ascii_whitespace() => self.i += 1,
                (Some(b'/'), Some(b'/')) | (Some(b'#'), Some(b'!')) => {
                    while self.peek().is_some_and(|c| c != b'\n') {
                        self.i += 1;
                    }
                }
                (Some(b'/'), Some(b'*')) => {
                    self.i += 2;
                    while self.i + 1 < self.s.len() && &self.s[self.i..self.i + 2] != b"*/" {
                        self.i += 1;
                    }
                    self.i = (self.i + 2).min(self.s.len());
                }
                _ => return,
            }
        }
    }

    fn ident(&mut self) -> &'a str {
        let start = self.i;
        while self
            .peek()
            .is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_')
        {
            self.i += 1;
        }
        std::str::from_utf8(&self.s[start..self.i]).unwrap_or("")
    }

    fn quoted(&mut self, q: u8) -> Result<(), String> {
        self.i += 1;
        while let Some(c) = self.peek() {
            self.i += 1;
            if c == b'\\' {
                self.i += 1;
            } else if c == q {
                return Ok(());
            }
        }
        self.fail("unterminated string")
    }

    /// Whether an identifier followed by a single `:` starts here (a struct field).
    fn at_field(&self) -> bool {
        let mut j = self.i;
        if !self
            .s
            .get(j)
            .is_some_and(|c| c.is_ascii_alphabetic() || *c == b'_')
        {
            return false;
        }
        while self
            .s
            .get(j)
            .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_')
        {
            j += 1;
        }
        while self.s.get(j).is_some_and(|c| c.is_ascii_whitespace()) {
            j += 1;
        }
        self.s.get(j) == Some(&b':') && self.s.get(j + 1) != Some(&b':')
    }

    fn value(&mut self) -> Result<Node, String> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return self.fail("values nested too deeply");
        }
        let node = self.value_inner();
        self.depth -= 1;
        node
    }

    fn value_inner(&mut self) -> Result<Node, String> {
        self.skip_ws();
        let start = self.i;
        let kind = match self.peek() {
            None => return self.fail("unexpected end"),
            Some(b'(') => self.parenthesised()?,
            Some(b'[') => Kind::Seq(self.items(b']')?),
            Some(b'{') => {
                self.items(b'}')?;
                Kind::Atom
            }
            Some(q @ (b'"' | b'\'')) => {
                self.quoted(q)?;
                Kind::Atom
            }
            Some(c) if c.is_ascii_alphabetic() || c == b'_' => {
                self.ident();
                let save = self.i;
                self.skip_ws();
                if self.peek() == Some(b'(') {
                    self.parenthesised()?
                } else {
                    self.i = save;
                    Kind::Atom
                }
            }
            Some(_) => {
                while self
                    .peek()
                    .is_some_and(|c| !c.is_ascii_whitespace() && !b",)]}:".contains(&c))
                {
                    self.i += 1;
                }
                if self.i == start {
                    return self.fail("expected a value");
                }
                Kind::Atom
            }
        };
        Ok(Node {
            start,
            end: self.i,
            kind,
        })
    }

    /// `( ... )`: a struct if its first item is `name:`, else a tuple.
    fn parenthesised(&mut self) -> Result<Kind, String> {
        self.i += 1;
        self.skip_ws();
        if !self.at_field() {
            self.i -= 1;
            return Ok(Kind::Seq(self.items(b')')?));
        }
        let mut fields = Vec::new();
        loop {
            self.skip_ws();
            if self.peek() == Some(b')') {
                let close = self.i;
                self.i += 1;
                return Ok(Kind::Struct { fields, close });
            }
            let name = self.ident().to_string();
            self.skip_ws();
            if self.peek() != Some(b':') {
                return self.fail("expected `:` after a field name");
            }
            self.i += 1;
            let v = self.value()?;
            fields.push((name, v));
            self.skip_ws();
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(b')') => {}
                _ => return self.fail("expected `,` or `)`"),
            }
        }
    }

    /// Comma-separated values up to `close` (the opening bracket is at `self.i`); map
    /// entries `k: v` are scanned as two values.
    fn items(&mut self, close: u8) -> Result<Vec<Node>, String> {
        self.i += 1;
        let mut items = Vec::new();
        loop {
            self.skip_ws();
            if self.peek() == Some(close) {
                self.i += 1;
                return Ok(items);
            }
            items.push(self.value()?);
            self.skip_ws();
            if self.peek() == Some(b':') {
                self.i += 1;
                self.value()?;
                self.skip_ws();
            }
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(c) if c == close => {}
                _ => return self.fail("expected `,` or a closing bracket"),
            }
        }
    }
}

/// Where the new value goes: replace a span, or insert `key: value` before `)`.
enum Edit {
    Replace(usize, usize),
    Insert { at: usize, key: String, comma: bool },
}

fn locate(text: &str, root: &Node, path: &[&str]) -> Result<Edit, String> {
    let mut node = root;
    for (depth, key) in path.iter().enumerate() {
        let here = path[..depth].join(".");
        let last = depth + 1 == path.len();
        node = match &node.kind {
            Kind::Struct { fields, close } => match fields.iter().find(|(n, _)| n == key) {
                Some((_, v)) => v,
                None if last => {
                    let before = text[..*close].trim_end();
                    let comma = !(before.ends_with(',') || before.ends_with('('));
                    return Ok(Edit::Insert {
                        at: *close,
                        key: key.to_string(),
                        comma,
                    });
                }
                None => {
                    return Err(format!(
                        "`{here}` has no field `{key}` (fields: {})",
                        fields
                            .iter()
                            .map(|f| f.0.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ));
                }
            },
            Kind::Seq(items) => match key.parse::<usize>() {
                Ok(k) => items.get(k).ok_or_else(|| {
                    format!(
                        "`{here}` has {} items; index {k} is out of range",
                        items.len()
                    )
                })?,
                Err(_) => items
                    .iter()
                    .find(|it| has_name(text, it, key))
                    .ok_or_else(|| format!("`{here}` has no item named \"{key}\""))?,
            },
            Kind::Atom => {
                return Err(format!("`{here}` is a plain value; it has no part `{key}`"));
            }
        };
    }
    Ok(Edit::Replace(node.start, node.end))
}

fn has_name(text: &str, item: &Node, name: &str) -> bool {
    match &item.kind {
        Kind::Struct { fields, .. } => fields
            .iter()
            .any(|(n, v)| n == "name" && text[v.start..v.end].trim_matches('"') == name),
        _ => false,
    }
}

/// Applies one `key.path=value` to RON text.
pub fn set_in_text(text: &str, assignment: &str) -> Result<String, String> {
    let (path, value) = assignment
        .split_once('=')
        .ok_or_else(|| format!("`{assignment}` is not of the form key.path=value"))?;
    let path: Vec<&str> = path.trim().split('.').collect();
    if path.iter().any(|p| p.is_empty()) {
        return Err(format!("`{assignment}` has an empty key"));
    }
    let mut scanner = Scanner {
        s: text.as_bytes(),
        i: 0,
        depth: 0,
    };
    let root = scanner.value()?;
    let value = value.trim();
    Ok(match locate(text, &root, &path)? {
        Edit::Replace(a, b) => format!("{}{}{}", &text[..a], value, &text[b..]),
        Edit::Insert { at, key, comma } => {
            let sep = if comma { ", " } else { "" };
            format!("{}{sep}{key}: {value}{}", &text[..at], &text[at..])
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"Scene( // a comment
    name: "x",
    time: (end: 1.0, step: Cfl(0.5)),
    bodies: [
        (name: "bed", velocity: (0.0, 0.0), material: M(a: 1, b: [1, 2])),
        (name: "ball", material: M(a: 2)),
    ],
)"#;

    #[test]
    fn replaces_nested_values_and_list_items_by_index_or_name() {
        let t = set_in_text(TEXT, "time.step=Fixed(1e-6)").unwrap();
        assert!(t.contains("step: Fixed(1e-6))"));
        let t = set_in_text(TEXT, "bodies.ball.material.a=7").unwrap();
        assert!(t.contains("M(a: 7)"));
        let t = set_in_text(TEXT, "bodies.0.velocity.1=-3.5").unwrap();
        assert!(t.contains("velocity: (0.0, -3.5)"));
    }

    #[test]
    fn inserts_a_missing_field() {
        let t = set_in_text(TEXT, "bodies.ball.tracked=true").unwrap();
        assert!(t.contains("M(a: 2), tracked: true)"), "{t}");
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let text = format!("{}1{}", "(".repeat(100_000), ")".repeat(100_000));
        assert!(
            set_in_text(&text, "a=1")
                .unwrap_err()
                .contains("nested too deeply")
        );
    }

    #[test]
    fn reports_bad_paths() {
        assert!(
            set_in_text(TEXT, "nope")
                .unwrap_err()
                .contains("key.path=value")
        );
        assert!(
            set_in_text(TEXT, "bodies.7.name=1")
                .unwrap_err()
                .contains("out of range")
        );
        assert!(
            set_in_text(TEXT, "bodies.rock.name=1")
                .unwrap_err()
                .contains("no item named")
        );
        assert!(
            set_in_text(TEXT, "name.x=1")
                .unwrap_err()
                .contains("plain value")
        );
    }
}

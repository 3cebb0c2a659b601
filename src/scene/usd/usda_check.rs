//! A scan of a `.usda` text layer before openusd parses it, for two things its parser gets
//! wrong on hostile input:
//!
//! - it descends recursively into every `{`, `(` and `[`, so nesting a few thousand levels
//!   deep overflows the stack: bracket depth is limited to [`MAX_NESTING`];
//! - a tuple with fewer values than its type has components (`(1, 2)` in a `point3f[]`)
//!   leaves the missing components uninitialised (openusd 0.6's `parse_tuple`): every
//!   numeric tuple in the value of a `float3`, `point3f[]`, `quatf`, `matrix4d`, … attribute
//!   must have exactly as many values as the type has components (rows for matrices).
//!
//! Strings, asset paths, prim paths and comments are skipped.

use crate::error::Reason;

/// Deepest bracket nesting accepted in a text layer: room for [`super::arcs::MAX_DEPTH`]
/// nested prims with their metadata and values.
pub(super) const MAX_NESTING: usize = 320;

/// `true` when `bytes` begin like a text layer.
pub(super) fn is_text(bytes: &[u8]) -> bool {
    bytes.starts_with(b"#usda")
}

/// Fails with the line of the first problem.
pub(super) fn check(text: &[u8]) -> Reason<()> {
    Scanner {
        text,
        i: 0,
        line: 1,
        depth: 0,
        tuple_type: None,
    }
    .run()
    .map_err(|(line, reason)| format!("line {line}: {reason}"))
}

/// The type whose value is being read: its name, components, and the bracket depth of its
/// declaration (the value ends at a line break at that depth).
struct TupleType<'a> {
    name: &'a str,
    arity: usize,
    depth: usize,
}

struct Scanner<'a> {
    text: &'a [u8],
    i: usize,
    line: usize,
    depth: usize,
    tuple_type: Option<TupleType<'a>>,
}

impl<'a> Scanner<'a> {
    fn run(mut self) -> Result<(), (usize, String)> {
        while self.i < self.text.len() {
            let c = self.text[self.i];
            self.i += 1;
            match c {
                b'\n' => {
                    if self
                        .tuple_type
                        .as_ref()
                        .is_some_and(|t| t.depth == self.depth)
                    {
                        self.tuple_type = None;
                    }
                    self.line += 1;
                }
                b'#' => self.skip_until(b"\n"),
                b'"' | b'\'' => self.skip_string(c),
                b'@' => {
                    let close: &[u8] = if self.rest().starts_with(b"@@") {
                        self.i += 2;
                        b"@@@"
                    } else {
                        b"@"
                    };
                    self.skip_until(close);
                }
                b'<' => self.skip_until(b">"),
                b'{' | b'(' | b'[' => {
                    if c == b'(' {
                        self.check_tuple()?;
                    }
                    self.depth += 1;
                    if self.depth > MAX_NESTING {
                        let reason = format!("brackets nested more than {MAX_NESTING} levels deep");
                        return Err((self.line, reason));
                    }
                }
                b'}' | b')' | b']' => self.depth = self.depth.saturating_sub(1),
                c if c.is_ascii_alphabetic() || c == b'_' => self.word(),
                _ => {}
            }
        }
        Ok(())
    }

    fn rest(&self) -> &'a [u8] {
        &self.text[self.i..]
    }

    /// Reads an identifier; a tuple type name starts a value whose tuples are checked.
    fn word(&mut self) {
        let start = self.i - 1;
        while self.i < self.text.len()
            && (self.text[self.i].is_ascii_alphanumeric() || b"_:.".contains(&self.text[self.i]))
        {
            self.i += 1;
        }
        let word = std::str::from_utf8(&self.text[start..self.i]).unwrap_or("");
        if let Some(arity) = tuple_arity(word) {
            self.tuple_type = Some(TupleType {
                name: word,
                arity,
                depth: self.depth,
            });
        }
    }

    /// At a `(` in the value of a tuple type: a group of plain numbers must have the type's
    /// number of components. (Other groups — metadata, nested rows — are not tuples.)
    fn check_tuple(&self) -> Result<(), (usize, String)> {
        let Some(t) = &self.tuple_type else {
            return Ok(());
        };
        let rest = self.rest();
        let Some(end) = rest.iter().position(|&b| b == b')') else {
            return Ok(());
        };
        let group = &rest[..end];
        let numeric = group
            .iter()
            .all(|&b| b.is_ascii_alphanumeric() || b" \t\r\n,.+-".contains(&b));
        if !numeric || group.iter().all(u8::is_ascii_whitespace) {
            return Ok(());
        }
        let values = group
            .split(|&b| b == b',')
            .filter(|v| !v.iter().all(u8::is_ascii_whitespace))
            .count();
        if values != t.arity {
            let reason = format!(
                "a tuple of {values} values in a {} value, which needs {}",
                t.name, t.arity
            );
            return Err((self.line, reason));
        }
        Ok(())
    }

    /// Moves past the next `close` (to the end when there is none), counting lines.
    fn skip_until(&mut self, close: &[u8]) {
        let end = self
            .rest()
            .windows(close.len())
            .position(|w| w == close)
            .map_or(self.text.len(), |k| self.i + k + close.len());
        self.count_lines(end);
    }

    /// Moves past a string opened by `quote` (single or triple), where a backslash escapes.
    fn skip_string(&mut self, quote: u8) {
        let triple = [quote; 3];
        let close: &[u8] = if self.rest().starts_with(&triple[..2]) {
            self.i += 2;
            &triple
        } else {
            &triple[..1]
        };
        let mut j = self.i;
        while j < self.text.len() && !self.text[j..].starts_with(close) {
            j += if self.text[j] == b'\\' { 2 } else { 1 };
        }
        self.count_lines((j + close.len()).min(self.text.len()));
    }

    fn count_lines(&mut self, end: usize) {
        let end = end.min(self.text.len());
        self.line += self.text[self.i..end]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        self.i = end;
    }
}

/// The components of a tuple-valued type name (`point3f` 3, `quatd` 4, `matrix4d` rows of
/// 4, also as arrays `point3f[]`), `None` for any other word.
fn tuple_arity(word: &str) -> Option<usize> {
    if matches!(word, "quatf" | "quatd" | "quath") {
        return Some(4);
    }
    if word == "frame4d" {
        return Some(4);
    }
    let prefix = [
        "point", "normal", "vector", "color", "texCoord", "float", "double", "half", "int",
        "matrix",
    ]
    .into_iter()
    .find(|p| word.starts_with(p))?;
    let rest = &word[prefix.len()..];
    let n = match rest.as_bytes().first()? {
        b'2' => 2,
        b'3' => 3,
        b'4' => 4,
        _ => return None,
    };
    let suffix = &rest[1..];
    let ok = match prefix {
        "float" | "double" | "half" | "int" => suffix.is_empty(),
        "matrix" => suffix == "d",
        _ => matches!(suffix, "f" | "d" | "h"),
    };
    ok.then_some(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deep_brackets_are_refused_with_their_line() {
        let deep = format!("#usda 1.0\n{}", "def X \"A\" {\n".repeat(MAX_NESTING + 1));
        let e = check(deep.as_bytes()).unwrap_err();
        assert!(e.starts_with(&format!("line {}:", MAX_NESTING + 2)), "{e}");
        let shallow = format!(
            "#usda 1.0\n{}{}",
            "def X \"A\" {\n".repeat(MAX_NESTING),
            "}\n".repeat(MAX_NESTING)
        );
        assert!(check(shallow.as_bytes()).is_ok());
    }

    #[test]
    fn brackets_in_strings_paths_and_comments_do_not_count() {
        let noise = "\"{{{\" '(((' \"\"\"[[[\n{{\"\"\" @a{.usda@ </A{v=x}> # {{{{\n";
        let text = format!("#usda 1.0\n{}", noise.repeat(MAX_NESTING));
        assert!(check(text.as_bytes()).is_ok());
    }

    #[test]
    fn tuples_must_have_all_their_components() {
        let ok = "#usda 1.0\ndef Mesh \"M\" {\n    point3f[] points = [(0, 0, 0), (1, 0, 1e-3),\n        (-1, nan, 2)]\n    float2[] st = [(0, 1)] (interpolation = \"vertex\")\n    matrix4d m = ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1) )\n    double3 t.timeSamples = { 0: (1, 2, 3), 1: (4, 5, 6) }\n    int[] n = [3]\n}\n";
        assert!(check(ok.as_bytes()).is_ok());
        let short = ok.replace("(1, 0, 1e-3)", "(1, 0)");
        let e = check(short.as_bytes()).unwrap_err();
        assert_eq!(
            e,
            "line 3: a tuple of 2 values in a point3f value, which needs 3"
        );
        let long_row = ok.replace("(0, 1, 0, 0)", "(0, 1, 0)");
        assert!(check(long_row.as_bytes()).unwrap_err().contains("matrix4d"));
    }

    #[test]
    fn type_names() {
        assert_eq!(tuple_arity("point3f"), Some(3));
        assert_eq!(tuple_arity("float2"), Some(2));
        assert_eq!(tuple_arity("texCoord2f"), Some(2));
        assert_eq!(tuple_arity("matrix3d"), Some(3));
        assert_eq!(tuple_arity("quath"), Some(4));
        assert_eq!(tuple_arity("float"), None);
        assert_eq!(tuple_arity("float3x"), None);
        assert_eq!(tuple_arity("points"), None);
        assert_eq!(tuple_arity("int64"), None);
    }
}

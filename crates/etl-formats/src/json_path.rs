//! The path of the JSON value at a position of a document (`views[2].points[0].pixel[1]`),
//! so that a parse error names the field it stopped at.
//!
//! serde_json reports a failure by line and column only. The path is recovered by one
//! lexical pass over the text up to that position, keeping a stack of the open objects
//! (with the key being read) and arrays (with the index being read). It is run on a
//! failure only, so a good file reads at full speed, and it keeps etl-formats on its four
//! dependencies (the path is what `serde_path_to_error` would give, without a second
//! deserialisation).

/// One open container: an object with the key of the member being read (`None` before
/// its first key), or an array with the index of the element being read.
enum Open {
    Object(Option<String>),
    Array(usize),
}

/// The dotted path of the value being read at 1-based `line` and `column` of `text`, as
/// serde_json counts them (columns in bytes, the position being that of the last byte
/// read); `None` at the top level or if the text ends first. A position on the closing
/// bracket of a container names the container itself (serde_json reports a wrong length
/// or a missing field there).
pub(crate) fn path_at(text: &str, line: usize, column: usize) -> Option<String> {
    let end = byte_offset(text, line, column)?;
    let bytes = text.as_bytes();
    let mut stack: Vec<Open> = Vec::new();
    // Whether the next string of the innermost object is a key (after `{` or `,`).
    let mut want_key = false;
    let mut i = 0;
    while i < end.min(bytes.len()) {
        match bytes[i] {
            b'{' => {
                stack.push(Open::Object(None));
                want_key = true;
            }
            b'[' => stack.push(Open::Array(0)),
            b'}' | b']' => {
                stack.pop();
                want_key = false;
            }
            b',' => match stack.last_mut() {
                Some(Open::Array(k)) => *k += 1,
                Some(Open::Object(_)) => want_key = true,
                None => {}
            },
            b'"' => {
                let (s, next) = read_string(text, i)?;
                if want_key {
                    if let Some(Open::Object(key)) = stack.last_mut() {
                        *key = Some(s);
                    }
                    want_key = false;
                }
                i = next;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    render(&stack)
}

/// The byte offset just past 1-based (`line`, `column`), or `None` beyond the text.
fn byte_offset(text: &str, line: usize, column: usize) -> Option<usize> {
    let mut start = 0;
    for _ in 1..line {
        start += text[start..].find('\n')? + 1;
    }
    Some(start + column)
}

/// The JSON string starting at `open` (its quote): its text (escapes kept as written,
/// enough for a key) and the offset after its closing quote.
fn read_string(text: &str, open: usize) -> Option<(String, usize)> {
    let bytes = text.as_bytes();
    let mut i = open + 1;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' => i += 2,
            b'"' => return Some((text[open + 1..i].to_owned(), i + 1)),
            _ => i += 1,
        }
    }
    None
}

/// `a.b[2].c` from the open containers.
fn render(stack: &[Open]) -> Option<String> {
    let mut path = String::new();
    for open in stack {
        match open {
            Open::Object(Some(key)) => {
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(key);
            }
            Open::Object(None) => {}
            Open::Array(k) => path.push_str(&format!("[{k}]")),
        }
    }
    (!path.is_empty()).then_some(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path_of_error<T: serde::de::DeserializeOwned + core::fmt::Debug>(text: &str) -> Option<String> {
        let e = serde_json::from_str::<T>(text).unwrap_err();
        path_at(text, e.line(), e.column())
    }

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Point {
        world_mm: [f64; 3],
        pixel: [f64; 2],
    }

    #[derive(Debug, serde::Deserialize)]
    #[allow(dead_code)]
    struct View {
        e_in_ma: f64,
        points: Vec<Point>,
    }

    #[derive(Debug, serde::Deserialize)]
    #[allow(dead_code)]
    struct File {
        kf_x: [f64; 4],
        views: Vec<View>,
    }

    /// The paths serde_path_to_error would give, for each kind of error serde_json reports.
    #[test]
    fn names_the_field_of_each_kind_of_error() {
        let good_view = r#"{"e_in_ma": 1, "points": [{"world_mm": [0, 0, 0], "pixel": [1, 2]}]}"#;
        let cases = [
            // a wrong type deep inside
            (format!(r#"{{"kf_x": [1, 2, 3, 4], "views": [{good_view}, {{"e_in_ma": 1, "points": [{{"world_mm": [0, 0, 0], "pixel": [1, "a"]}}]}}]}}"#), Some("views[1].points[0].pixel[1]")),
            // an array too short: reported at its closing bracket
            (format!(r#"{{"kf_x": [1, 2, 3], "views": [{good_view}]}}"#), Some("kf_x")),
            // a missing field: reported at the end of its object
            (r#"{"kf_x": [1, 2, 3, 4], "views": [{"points": []}]}"#.to_owned(), Some("views[0]")),
            // an unknown field (keys with escapes and commas inside strings are skipped)
            (r#"{"kf_x": [1, 2, 3, 4], "views": [{"e_in_ma": 1, "points": [{"world_mm": [0, 0, 0], "pixel": [1, 2], "n\"o,te": 1}]}]}"#.to_owned(), Some("views[0].points[0].n\\\"o,te")),
            // a missing top-level field: the top level has no path
            (r#"{"views": []}"#.to_owned(), None),
        ];
        for (text, expect) in cases {
            assert_eq!(path_of_error::<File>(&text).as_deref(), expect, "{text}");
        }
    }

    #[test]
    fn positions_beyond_the_text_have_no_path() {
        assert_eq!(path_at("{}", 3, 1), None);
        assert_eq!(path_at("{\"a\": [1,\n 2]}", 2, 2).as_deref(), Some("a[1]"));
    }
}

//! Mutations of a valid file's JSON, each at one place: a number made NaN, too large for
//! an f64 (1e999), huge (1e308) or negative; a key dropped or renamed; an array shortened.

#![allow(dead_code)]

use serde_json::Value;

/// One step of a path into a JSON document.
#[derive(Debug, Clone, PartialEq)]
pub enum Step {
    /// A member of an object.
    Key(String),
    /// An element of an array.
    Index(usize),
}

/// What is done at the place.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mutation {
    /// The number replaced by the token `NaN` (not JSON).
    NaN,
    /// The number replaced by `1e999` (beyond an f64).
    Overflow,
    /// The number replaced by 1e308.
    Huge,
    /// The number negated (or made -1 if it is 0).
    Negative,
    /// The member removed.
    Drop,
    /// The member's key renamed (`_renamed` appended).
    Rename,
    /// The array's last element removed.
    Shorten,
}

/// Every place of `v` with the mutations that apply there.
pub fn sites(v: &Value) -> Vec<(Vec<Step>, Mutation)> {
    fn walk(v: &Value, path: &mut Vec<Step>, out: &mut Vec<(Vec<Step>, Mutation)>) {
        match v {
            Value::Number(_) => {
                for m in [Mutation::NaN, Mutation::Overflow, Mutation::Huge, Mutation::Negative] {
                    out.push((path.clone(), m));
                }
            }
            Value::Array(a) => {
                if !a.is_empty() {
                    out.push((path.clone(), Mutation::Shorten));
                }
                for (i, x) in a.iter().enumerate() {
                    path.push(Step::Index(i));
                    walk(x, path, out);
                    path.pop();
                }
            }
            Value::Object(m) => {
                for (k, x) in m {
                    path.push(Step::Key(k.clone()));
                    out.push((path.clone(), Mutation::Drop));
                    out.push((path.clone(), Mutation::Rename));
                    walk(x, path, out);
                    path.pop();
                }
            }
            _ => {}
        }
    }
    let mut out = vec![];
    walk(v, &mut vec![], &mut out);
    out
}

/// A placeholder for a token that is not JSON, replaced in the text.
const TOKEN: &str = "@@etlcal-mutant@@";

/// `v` with `m` applied at `path`: the mutated document (with any non-JSON token as a
/// string placeholder) and its text as a file would hold it.
pub fn apply(v: &Value, path: &[Step], m: Mutation) -> (Value, String) {
    let mut out = v.clone();
    let (last, parent) = path.split_last().expect("a place inside the document");
    let mut at = &mut out;
    for step in parent {
        at = match step {
            Step::Key(k) => &mut at[k.as_str()],
            Step::Index(i) => &mut at[*i],
        };
    }
    let mut token = None;
    match (m, last) {
        (Mutation::Drop, Step::Key(k)) => {
            at.as_object_mut().unwrap().remove(k);
        }
        (Mutation::Rename, Step::Key(k)) => {
            let map = at.as_object_mut().unwrap();
            let x = map.remove(k).unwrap();
            map.insert(format!("{k}_renamed"), x);
        }
        _ => {
            let target = match last {
                Step::Key(k) => &mut at[k.as_str()],
                Step::Index(i) => &mut at[*i],
            };
            match m {
                Mutation::NaN => token = Some("NaN"),
                Mutation::Overflow => token = Some("1e999"),
                Mutation::Huge => *target = Value::from(1e308),
                Mutation::Negative => {
                    let x = target.as_f64().unwrap();
                    *target = match target.as_i64() {
                        Some(0) => Value::from(-1),
                        Some(i) => Value::from(-i),
                        None if x == 0.0 => Value::from(-1.0),
                        None => Value::from(-x),
                    };
                }
                Mutation::Shorten => {
                    target.as_array_mut().unwrap().pop();
                }
                _ => unreachable!("{m:?} at {last:?}"),
            }
            if token.is_some() {
                *target = Value::from(TOKEN);
            }
        }
    }
    let mut text = serde_json::to_string_pretty(&out).unwrap();
    if let Some(token) = token {
        text = text.replace(&format!("\"{TOKEN}\""), token);
    }
    (out, text)
}

/// The keys along `path` (the mutated field and the fields holding it), innermost first;
/// for a dropped or renamed member, its own key.
pub fn keys_along(path: &[Step]) -> Vec<&str> {
    path.iter()
        .rev()
        .filter_map(|s| match s {
            Step::Key(k) => Some(k.as_str()),
            Step::Index(_) => None,
        })
        .collect()
}

/// `path` as the optional-key lists write it: `views[].e_com_ma`.
pub fn pattern(path: &[Step]) -> String {
    let mut s = String::new();
    for step in path {
        match step {
            Step::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Step::Index(_) => s.push_str("[]"),
        }
    }
    s
}

/// Where `read` (the value read back, as JSON) differs from `written` (the mutated file),
/// but for keys of `optional` that one has and the other lacks (a documented default); an
/// empty list or null left out by the writer counts as absent.
pub fn difference(written: &Value, read: &Value, path: &mut Vec<Step>, optional: &[&str]) -> Option<String> {
    let here = |path: &[Step]| pattern(path);
    match (written, read) {
        (Value::Number(a), Value::Number(b)) => {
            (a.as_f64() != b.as_f64()).then(|| format!("{}: {a} written, {b} read", here(path)))
        }
        (Value::Array(a), Value::Array(b)) => {
            if a.len() != b.len() {
                return Some(format!("{}: {} elements written, {} read", here(path), a.len(), b.len()));
            }
            a.iter().zip(b).enumerate().find_map(|(i, (x, y))| {
                path.push(Step::Index(i));
                let d = difference(x, y, path, optional);
                path.pop();
                d
            })
        }
        (Value::Object(a), Value::Object(b)) => {
            for k in a.keys().chain(b.keys()) {
                path.push(Step::Key(k.clone()));
                let d = match (a.get(k), b.get(k)) {
                    (Some(x), Some(y)) => difference(x, y, path, optional),
                    (Some(x), None) if is_empty(x) && optional.contains(&here(path).as_str()) => None,
                    (None, Some(_)) if optional.contains(&here(path).as_str()) => None,
                    (x, y) => Some(format!("{}: {x:?} written, {y:?} read", here(path))),
                };
                path.pop();
                if d.is_some() {
                    return d;
                }
            }
            None
        }
        (a, b) => (a != b).then(|| format!("{}: {a} written, {b} read", here(path))),
    }
}

fn is_empty(v: &Value) -> bool {
    matches!(v, Value::Null) || v.as_array().is_some_and(Vec::is_empty)
}

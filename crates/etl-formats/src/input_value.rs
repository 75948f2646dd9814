//! A refused value as [`crate::Error::InvalidInput`] keeps it: text, printed the way
//! messages print it.

use std::path::{Path, PathBuf};

/// A value as bad input keeps it ([`crate::Error::invalid_value`]), the way messages print it:
/// numbers compactly ([`crate::compact`]: `1e308`, not 309 digits; `NaN`), text as given,
/// a path as displayed, a list as `[a, b]`.
pub trait InputValue {
    /// The value as text.
    fn to_input_value(&self) -> String;
}

impl InputValue for f64 {
    fn to_input_value(&self) -> String {
        crate::compact(*self)
    }
}

macro_rules! integer_input_values {
    ($($t:ty),*) => {$(
        impl InputValue for $t {
            fn to_input_value(&self) -> String {
                self.to_string()
            }
        }
    )*};
}
integer_input_values!(u8, u16, u32, u64, usize, i8, i16, i32, i64, isize);

impl InputValue for str {
    fn to_input_value(&self) -> String {
        self.to_owned()
    }
}

impl InputValue for String {
    fn to_input_value(&self) -> String {
        self.clone()
    }
}

impl InputValue for Path {
    fn to_input_value(&self) -> String {
        self.display().to_string()
    }
}

impl InputValue for PathBuf {
    fn to_input_value(&self) -> String {
        self.display().to_string()
    }
}

impl<T: InputValue> InputValue for [T] {
    fn to_input_value(&self) -> String {
        let items: Vec<String> = self.iter().map(InputValue::to_input_value).collect();
        format!("[{}]", items.join(", "))
    }
}

impl<T: InputValue, const N: usize> InputValue for [T; N] {
    fn to_input_value(&self) -> String {
        self.as_slice().to_input_value()
    }
}

impl<T: InputValue> InputValue for Vec<T> {
    fn to_input_value(&self) -> String {
        self.as_slice().to_input_value()
    }
}

impl<T: InputValue + ?Sized> InputValue for &T {
    fn to_input_value(&self) -> String {
        (**self).to_input_value()
    }
}

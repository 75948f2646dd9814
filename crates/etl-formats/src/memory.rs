//! The memory budget: a request whose size the caller sets (map sizes, a simulation's views)
//! is costed before anything is allocated for it, and refused past the budget in one line
//! naming the option and the estimate, instead of dying in the allocator.
//!
//! The budget is [`DEFAULT_FRACTION`] of the machine's physical memory (Linux:
//! `/proc/meminfo`'s `MemTotal`), or the bytes in the environment variable
//! [`BUDGET_ENV`] (`ETLCAL_MEMORY_BUDGET=8G`; suffixes K, M, G, T in powers of 1024; `0`
//! or `off` checks nothing). A value that does not parse is refused, naming the variable,
//! rather than ignored. Where physical memory cannot be read (another system) and the
//! variable is not set, only the documented caps of each option apply.
//!
//! ```
//! use etl_formats::memory::{check_memory, parse_budget};
//! assert_eq!(parse_budget("8G").unwrap(), Some(8 << 30));
//! assert_eq!(parse_budget("off").unwrap(), None);
//! assert!(parse_budget("8GB").is_err());
//! // Four bytes are within any budget.
//! check_memory("size", 4).unwrap();
//! ```

use crate::{Error, Result};

/// The environment variable that sets the budget, in bytes (`8G`, `512M`, `0`/`off`).
pub const BUDGET_ENV: &str = "ETLCAL_MEMORY_BUDGET";

/// The default budget's share of physical memory: half, so that the estimate's slack and
/// the rest of the machine fit beside a request at the budget.
pub const DEFAULT_FRACTION: f64 = 0.5;

/// `text` as a budget in bytes: `None` for `0` or `off` (no check). Errors: anything but
/// a whole number with an optional K/M/G/T suffix.
pub fn parse_budget(text: &str) -> Result<Option<u64>> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("off") {
        return Ok(None);
    }
    let (digits, shift) = match t.as_bytes().last().map(u8::to_ascii_uppercase) {
        Some(b'K') => (&t[..t.len() - 1], 10),
        Some(b'M') => (&t[..t.len() - 1], 20),
        Some(b'G') => (&t[..t.len() - 1], 30),
        Some(b'T') => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let refuse = || {
        Error::invalid_value(
            BUDGET_ENV,
            text,
            format!("{BUDGET_ENV}={text:?} is not a number of bytes (say 8G, 512M, 1000000, or off)"),
        )
    };
    let n: u64 = digits.parse().map_err(|_| refuse())?;
    let bytes = n.checked_mul(1u64 << shift).ok_or_else(refuse)?;
    Ok((bytes > 0).then_some(bytes))
}

/// The budget in bytes, `None` when nothing is checked (see the module doc).
pub fn budget_bytes() -> Result<Option<u64>> {
    Ok(budget()?.map(|(bytes, _)| bytes))
}

/// The budget in bytes and where it comes from (for the refusal's message).
fn budget() -> Result<Option<(u64, String)>> {
    match std::env::var(BUDGET_ENV) {
        Ok(text) => Ok(parse_budget(&text)?.map(|b| (b, BUDGET_ENV.to_string()))),
        Err(std::env::VarError::NotUnicode(_)) => Err(Error::invalid(BUDGET_ENV, format!("{BUDGET_ENV} is not UTF-8"))),
        Err(std::env::VarError::NotPresent) => Ok(physical_memory_bytes()
            .map(|b| ((b as f64 * DEFAULT_FRACTION) as u64, format!("half of physical memory; {BUDGET_ENV} sets it")))),
    }
}

/// The machine's physical memory, from `/proc/meminfo` (Linux); `None` elsewhere.
fn physical_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Refuses a request of `option` estimated at `estimate_bytes` when it is above the
/// budget: `"size needs about 40 GB, above the memory budget of 12 GB (half of physical
/// memory; ETLCAL_MEMORY_BUDGET sets it)"`.
pub fn check_memory(option: &str, estimate_bytes: u64) -> Result<()> {
    let Some((budget, source)) = budget()? else { return Ok(()) };
    if estimate_bytes <= budget {
        return Ok(());
    }
    Err(Error::invalid(
        option,
        format!(
            "{option} needs about {}, above the memory budget of {} ({source}): refused before allocating",
            gigabytes(estimate_bytes),
            gigabytes(budget)
        ),
    ))
}

/// `bytes` for people: `"40 GB"`, `"1.5 GB"`, `"0.02 GB"` (10^9 bytes).
fn gigabytes(bytes: u64) -> String {
    let gb = bytes as f64 / 1e9;
    if gb >= 10.0 {
        format!("{gb:.0} GB")
    } else if gb >= 0.1 {
        format!("{gb:.1} GB")
    } else {
        format!("{gb:.3} GB")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_parse_with_binary_suffixes_and_bad_text_is_refused_naming_the_variable() {
        assert_eq!(parse_budget("1000").unwrap(), Some(1000));
        assert_eq!(parse_budget("512m").unwrap(), Some(512 << 20));
        assert_eq!(parse_budget(" 2T ").unwrap(), Some(2 << 40));
        assert_eq!(parse_budget("0").unwrap(), None);
        assert_eq!(parse_budget("OFF").unwrap(), None);
        for bad in ["", "8GB", "-1", "1.5G", "half", "99999999999T"] {
            let e = parse_budget(bad).unwrap_err().to_string();
            assert!(e.contains("ETLCAL_MEMORY_BUDGET=") && e.contains("is not a number of bytes"), "{bad}: {e}");
        }
    }

    #[test]
    fn gigabytes_print_with_fixed_precision() {
        assert_eq!(gigabytes(42_000_000_000), "42 GB");
        assert_eq!(gigabytes(2_147_483_648), "2.1 GB");
        assert_eq!(gigabytes(20_000_000), "0.020 GB");
    }

    #[test]
    fn physical_memory_is_read_on_linux() {
        if cfg!(target_os = "linux") {
            let b = physical_memory_bytes().unwrap();
            assert!(b > 1 << 28, "{b}");
        }
    }
}

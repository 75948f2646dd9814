//! `manual`: a stage moved by hand. Each move prints where to put the board on stderr and
//! waits for a line on stdin: Enter (the board is where asked) or the position read off
//! the micrometer, mm (recorded instead). The lens-off poses are asked for the same way.
//! A closed stdin ends the capture (the link is lost).

use std::io::{BufRead, Write};

use super::Stage;
use crate::error::{Error, ErrorKind, Result};

/// A hand-moved stage prompting on `W` and reading `R`.
pub struct ManualStage<R: BufRead, W: Write> {
    input: R,
    prompt: W,
    position_mm: Option<f64>,
}

/// The manual stage of the terminal: prompts on stderr, reads stdin.
pub type StdioManualStage = ManualStage<std::io::BufReader<std::io::Stdin>, std::io::Stderr>;

impl StdioManualStage {
    /// The manual stage on stdin and stderr.
    pub fn stdio() -> StdioManualStage {
        ManualStage::new(std::io::BufReader::new(std::io::stdin()), std::io::stderr())
    }
}

impl<R: BufRead, W: Write> ManualStage<R, W> {
    /// A manual stage reading answers from `input` and prompting on `prompt`.
    pub fn new(input: R, prompt: W) -> Self {
        ManualStage { input, prompt, position_mm: None }
    }

    /// Prints `question` and reads one answer line (without its line break).
    fn ask(&mut self, question: &str) -> Result<String> {
        let name = self.name();
        let lost = |e: String| Error::device(&name, ErrorKind::LinkLost, e);
        writeln!(self.prompt, "etlcal: {question}").map_err(|e| lost(e.to_string()))?;
        self.prompt.flush().map_err(|e| lost(e.to_string()))?;
        let mut line = String::new();
        let n = self.input.read_line(&mut line).map_err(|e| lost(e.to_string()))?;
        if n == 0 {
            return Err(lost("stdin closed: no answer to the prompt".into()));
        }
        Ok(line.trim().to_owned())
    }
}

impl<R: BufRead, W: Write> Stage for ManualStage<R, W> {
    fn name(&self) -> String {
        "stage manual".into()
    }

    fn move_mm(&mut self, z_mm: f64) -> Result<f64> {
        let mut question =
            format!("move the board to {z_mm:.4} mm, then press Enter (or type the position you read, mm)");
        loop {
            let answer = self.ask(&question)?;
            if answer.is_empty() {
                self.position_mm = Some(z_mm);
                return Ok(z_mm);
            }
            match answer.parse::<f64>() {
                Ok(z) if z.is_finite() => {
                    self.position_mm = Some(z);
                    return Ok(z);
                }
                _ => question = format!("'{answer}' is not a position in mm: press Enter at {z_mm:.4} mm or type it"),
            }
        }
    }

    fn position_mm(&mut self) -> Result<f64> {
        match self.position_mm {
            Some(z) => Ok(z),
            None => {
                let answer = self.ask("type the stage position you read, mm")?;
                let z = answer.parse::<f64>().ok().filter(|z| z.is_finite()).ok_or_else(|| {
                    Error::device(self.name(), ErrorKind::InvalidInput, format!("'{answer}' is not a position in mm"))
                })?;
                self.position_mm = Some(z);
                Ok(z)
            }
        }
    }

    fn home(&mut self) -> Result<()> {
        self.ask("move the stage to its reference (zero), then press Enter")?;
        self.position_mm = Some(0.0);
        Ok(())
    }

    fn limits_mm(&mut self) -> Result<[f64; 2]> {
        Ok([f64::NEG_INFINITY, f64::INFINITY])
    }

    fn present_offstate_pose(&mut self, k: usize, count: usize) -> Result<()> {
        let question = format!(
            "lens-off view {} of {count}: tilt the lens-off board by 15-30 degrees about a new axis, filling most of the frame, then press Enter",
            k + 1
        );
        self.ask(&question)?;
        self.position_mm = None;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enter_keeps_the_asked_position_and_a_number_replaces_it() {
        let mut prompts = Vec::new();
        let mut s = ManualStage::new(std::io::Cursor::new("\nabc\n21.995\n"), &mut prompts);
        assert_eq!(s.move_mm(10.0).unwrap(), 10.0);
        assert_eq!(s.move_mm(22.0).unwrap(), 21.995);
        let e = s.move_mm(5.0).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::LinkLost);
        assert!(e.to_string().starts_with("stage manual: stdin closed"), "{e}");
        let text = String::from_utf8(prompts).unwrap();
        assert!(text.contains("move the board to 22.0000 mm") && text.contains("'abc' is not a position"), "{text}");
    }
}

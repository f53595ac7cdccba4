//! Numbers as regolith prints them: [`Num`] in every CSV and summary, [`Seconds`] for a
//! moment named in a message. Below everything that prints, so an error message and an output
//! file write a number the same way.

/// A number as the CSV files write it: the shortest text that reads back to the same `f64`,
/// in plain decimals from 1e-4 up to 1e16 (`0.455`, `-3.55`, `0`) and in exponent form
/// beyond (`-3.42e-17`), as Python's `repr` does. Before, every number had an exponent
/// (`4.55e-1`, `0e0`), which is exact but hard to read in a spreadsheet.
#[derive(Clone, Copy, Debug)]
pub struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-4..1e16).contains(&a) || !a.is_finite() {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// A simulated time as messages print it: nine significant digits, then the shortest text
/// (`0.3` for a clock that summed its steps to 0.30000000000000004, `0.0123456789`): a
/// message names a moment, which nine digits place to well under a step.
#[derive(Clone, Copy, Debug)]
pub struct Seconds(pub f64);

impl std::fmt::Display for Seconds {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let rounded: f64 = format!("{:.8e}", self.0).parse().unwrap_or(self.0);
        write!(f, "{}", Num(rounded))
    }
}

#[cfg(test)]
mod tests {
    use super::{Num, Seconds};

    #[test]
    fn message_times_have_nine_significant_digits() {
        assert_eq!(Seconds(0.1 + 0.2).to_string(), "0.3");
        assert_eq!(Seconds(0.012345678901234567).to_string(), "0.0123456789");
        assert_eq!(Seconds(0.0).to_string(), "0");
        assert_eq!(Seconds(20.0).to_string(), "20");
    }

    #[test]
    fn csv_numbers_are_plain_where_readable_and_read_back_exactly() {
        let cases = [
            (0.0, "0"),
            (0.455, "0.455"),
            (-3.55, "-3.55"),
            (4.550000000000001e-1, "0.4550000000000001"),
            (1e-4, "0.0001"),
            (9.9e-5, "9.9e-5"),
            (-3.42184996939323e-17, "-3.42184996939323e-17"),
            (1e16, "1e16"),
            (123456.0, "123456"),
        ];
        for (v, text) in cases {
            assert_eq!(Num(v).to_string(), text);
        }
        // Every float reads back bit for bit, across the whole range.
        let mut x = 1.234_567_890_123_456_7e-300_f64;
        while x < 1e300 {
            for v in [x, -x, x * (1.0 + f64::EPSILON)] {
                let back: f64 = Num(v).to_string().parse().unwrap();
                assert_eq!(back.to_bits(), v.to_bits(), "{v:e}");
            }
            x *= 3.7;
        }
    }
}

//! `--frame-range`: which frames of a `--frames` sequence `glint render`
//! draws, numbered and posed as in the whole run, in the forms render farms
//! write: glint's own `FIRST..END` (END not included), and the inclusive
//! forms of Slurm's job arrays and Open Job Description's range expressions:
//! `N`, `A-B`, `A-B:STEP` and comma-separated lists of them (`1,3,5-7`).
//! Frames are drawn once each, in ascending order, whatever order the list
//! gives them in.

use glint::text::quote;

/// The most items a comma-separated list may have (each may name every frame
/// of a sequence: marking them is bounded by this times `--frames`).
const MAX_ITEMS: usize = 1_000;

/// One item of a frame range: frames `first`, `first + step`, … up to and
/// including `last`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Item {
    first: u32,
    last: u32,
    step: u32,
}

/// A `--frame-range` as given, checked against a sequence by [`FrameRange::frames`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameRange {
    text: String,
    items: Vec<Item>,
}

/// Parse a `--frame-range` (clap's value parser).
pub fn parse_frame_range(s: &str) -> Result<FrameRange, String> {
    let text = s.trim().to_string();
    let forms = "expected FIRST..END (END not included, such as 0..100), or frames as a farm lists them: \
                 N, A-B, A-B:STEP (inclusive) or a comma-separated list of those, such as 1,3,5-7";
    if text.is_empty() {
        return Err(format!("an empty frame range: {forms}"));
    }
    if let Some((a, b)) = text.split_once("..") {
        let (first, end) = (number(a, forms)?, number(b, forms)?);
        if first >= end {
            return Err(format!("{} is empty: FIRST..END takes frames FIRST up to (not including) END", quote(&text)));
        }
        return Ok(FrameRange { items: vec![Item { first, last: end - 1, step: 1 }], text });
    }
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() > MAX_ITEMS {
        return Err(format!("a frame range lists at most {MAX_ITEMS} items, not {}", parts.len()));
    }
    let items = parts.iter().map(|part| item(part.trim(), forms)).collect::<Result<_, _>>()?;
    Ok(FrameRange { text, items })
}

/// One comma-separated item: `N`, `A-B` or `A-B:STEP`.
fn item(part: &str, forms: &str) -> Result<Item, String> {
    let (span, step) = match part.split_once(':') {
        Some((span, step)) => (span, number(step, forms)?),
        None => (part, 1),
    };
    if step == 0 {
        return Err(format!("{}: a step of 0 never moves on; {forms}", quote(part)));
    }
    let (first, last) = match span.split_once('-') {
        Some((a, b)) => (number(a, forms)?, number(b, forms)?),
        None if part.contains(':') => return Err(format!("{}: a step needs a range, A-B:STEP; {forms}", quote(part))),
        None => {
            let n = number(span, forms)?;
            (n, n)
        }
    };
    if first > last {
        return Err(format!("{} runs backwards ({first} is after {last}): ranges count up", quote(part)));
    }
    Ok(Item { first, last, step })
}

/// A frame number: a whole number a frame can have.
fn number(s: &str, forms: &str) -> Result<u32, String> {
    let s = s.trim();
    if s.is_empty() || !s.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("{} is not a frame number; {forms}", quote(s)));
    }
    s.parse().map_err(|_| format!("frame {} is past the largest frame number, {}", quote(s), u32::MAX))
}

impl FrameRange {
    /// Its frames of a sequence of `total` frames, ascending, each once; an
    /// error naming the first frame past the sequence's end.
    pub fn frames(&self, total: u32) -> Result<Vec<u32>, String> {
        if let Some(past) = self.items.iter().find(|i| i.last >= total) {
            return Err(format!(
                "--frame-range {} reaches frame {}, past the sequence's {total} frames (--frames; numbered from 0)",
                quote(&self.text),
                past.last
            ));
        }
        // Marked, then listed: ascending and each once, in no more room than the sequence.
        let mut wanted = vec![false; total as usize];
        for i in &self.items {
            for frame in (i.first..=i.last).step_by(i.step as usize) {
                wanted[frame as usize] = true;
            }
        }
        Ok((0..total).filter(|&f| wanted[f as usize]).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(s: &str, total: u32) -> Result<Vec<u32>, String> {
        parse_frame_range(s)?.frames(total)
    }

    #[test]
    fn every_form_lists_its_frames() {
        assert_eq!(frames("2..5", 10), Ok(vec![2, 3, 4]), "glint's own, END not included");
        assert_eq!(frames(" 0 .. 1", 10), Ok(vec![0]));
        assert_eq!(frames("7", 10), Ok(vec![7]));
        assert_eq!(frames("1-4", 10), Ok(vec![1, 2, 3, 4]), "inclusive, as Slurm and OpenJD count");
        assert_eq!(frames("1-9:3", 10), Ok(vec![1, 4, 7]));
        assert_eq!(frames("0-8:4", 10), Ok(vec![0, 4, 8]), "the last is taken when the step lands on it");
        assert_eq!(frames(" 1,3, 5-7 ", 10), Ok(vec![1, 3, 5, 6, 7]));
        assert_eq!(frames("5-7,1,6", 10), Ok(vec![1, 5, 6, 7]), "ascending, each once");
        assert_eq!(frames("9-9", 10), Ok(vec![9]));
    }

    #[test]
    fn bad_ranges_say_what_was_expected() {
        let error = |s: &str, total| frames(s, total).unwrap_err();
        assert!(error("", 10).contains("an empty frame range"));
        assert!(error("3..3", 10).contains("'3..3' is empty"));
        assert!(error("5..2", 10).contains("is empty"));
        assert!(error("5-2", 10).contains("runs backwards (5 is after 2)"));
        assert!(error("1-4:0", 10).contains("a step of 0"));
        assert!(error("1-x", 10).contains("'x' is not a frame number"));
        assert!(error("-3", 10).contains("'' is not a frame number"));
        assert!(error("1,,2", 10).contains("not a frame number"));
        assert!(error("4294967296", 10).contains("frame '4294967296' is past the largest frame number"));
        assert!(error("1..99999999999", 10).contains("past the largest frame number"));
        assert!(error("-1..3", 10).contains("'-1' is not a frame number"));
        assert!(error("0-4294967295", 10).contains("reaches frame 4294967295, past the sequence's 10 frames"));
        assert!(error("3,10", 10).contains("reaches frame 10"), "frames are numbered from 0");
        assert!(error(&"1,".repeat(MAX_ITEMS + 1), 10).contains("at most 1000 items"));
        assert!(error("3:2", 10).contains("a step needs a range"));
    }
}

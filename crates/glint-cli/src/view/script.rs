//! `glint view --at FRAME:ACTION`: window actions at given frames, so a run
//! under a virtual display (CI) can resize, minimise and take screenshots, and
//! change what the keys change (density, time of day).

use std::path::PathBuf;

/// Something done to the window before drawing a frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Ask for this inner size in pixels.
    Resize(u32, u32),
    /// Minimise the window.
    Minimize,
    /// Restore it.
    Restore,
    /// Write the last drawn frame to this PNG.
    Screenshot(PathBuf),
    /// Draw this share of every tile (`[` and `]`).
    Density(f32),
    /// Move the sun and sky to this hour (`,` and `.`).
    TimeOfDay(f32),
    /// Show or hide the overlay (`H`).
    Overlay(bool),
    /// Set a control of the scene (as its panel would) to a value.
    Set(String, f32),
    /// Write the last frame's statistics (each view's) and the scene time as JSON.
    Stats(PathBuf),
}

/// An [`Action`] and the frame (counted from 1) before which it happens.
#[derive(Clone, Debug, PartialEq)]
pub struct Scripted {
    /// Frame number, from 1.
    pub frame: u32,
    /// What happens.
    pub action: Action,
}

/// Parse `FRAME:resize=WxH`, `FRAME:minimize`, `FRAME:restore`,
/// `FRAME:screenshot=PATH`, `FRAME:density=D`, `FRAME:time_of_day=H`,
/// `FRAME:overlay=on|off`, `FRAME:set=CONTROL=VALUE` or `FRAME:stats=PATH`.
pub fn parse_at(s: &str) -> Result<Scripted, String> {
    let expected = "expected FRAME:resize=WxH, FRAME:minimize, FRAME:restore, FRAME:screenshot=PATH, \
                    FRAME:density=D, FRAME:time_of_day=H, FRAME:overlay=on|off, FRAME:set=CONTROL=VALUE \
                    or FRAME:stats=PATH";
    let (frame, action) = s.split_once(':').ok_or_else(|| expected.to_string())?;
    let frame = frame
        .trim()
        .parse::<u32>()
        .ok()
        .filter(|&f| f >= 1)
        .ok_or_else(|| "the frame must be a whole number from 1".to_string())?;
    let action = match action.split_once('=') {
        None if action == "minimize" => Action::Minimize,
        None if action == "restore" => Action::Restore,
        Some(("screenshot", path)) if !path.is_empty() => Action::Screenshot(PathBuf::from(path)),
        Some(("resize", size)) => {
            let (w, h) = crate::parse_size(size)?;
            Action::Resize(w, h)
        }
        Some(("density", d)) => Action::Density(crate::parse_density(d)?),
        Some(("time_of_day", h)) => Action::TimeOfDay(crate::parse_hours(h)?),
        Some(("overlay", "on")) => Action::Overlay(true),
        Some(("overlay", "off")) => Action::Overlay(false),
        Some(("stats", path)) if !path.is_empty() => Action::Stats(PathBuf::from(path)),
        Some(("set", setting)) => match setting.split_once('=') {
            Some((id, value)) if !id.is_empty() => match value.parse::<f32>() {
                Ok(v) if v.is_finite() => Action::Set(id.to_owned(), v),
                _ => return Err("the value of a control must be a number".into()),
            },
            _ => return Err(expected.into()),
        },
        _ => return Err(expected.into()),
    };
    Ok(Scripted { frame, action })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_each_action_and_rejects_the_rest() {
        assert_eq!(parse_at("3:resize=200x100"), Ok(Scripted { frame: 3, action: Action::Resize(200, 100) }));
        assert_eq!(parse_at("1:minimize").map(|s| s.action), Ok(Action::Minimize));
        assert_eq!(parse_at("9:restore").map(|s| s.action), Ok(Action::Restore));
        assert_eq!(parse_at("4:screenshot=a:b.png").map(|s| s.action), Ok(Action::Screenshot("a:b.png".into())));
        assert_eq!(parse_at("2:density=0.25").map(|s| s.action), Ok(Action::Density(0.25)));
        assert_eq!(parse_at("2:time_of_day=18.5").map(|s| s.action), Ok(Action::TimeOfDay(18.5)));
        assert_eq!(parse_at("5:overlay=off").map(|s| s.action), Ok(Action::Overlay(false)));
        assert_eq!(parse_at("5:set=post.0.1.on=0").map(|s| s.action), Ok(Action::Set("post.0.1.on".into(), 0.0)));
        assert_eq!(parse_at("6:stats=s.json").map(|s| s.action), Ok(Action::Stats("s.json".into())));
        for bad in [
            "resize=2x2",
            "0:minimize",
            "x:minimize",
            "2:shrink",
            "2:resize=0x5",
            "2:screenshot=",
            "2:density=2",
            "2:time_of_day=25",
            "2:overlay=maybe",
            "2:set=shadows",
            "2:set=shadows=yes",
            "2:set==1",
            "2:stats=",
        ] {
            assert!(parse_at(bad).is_err(), "{bad}");
        }
    }
}

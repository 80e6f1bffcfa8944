//! The error screen: when `marionette run` cannot start (a broken
//! configuration, a motion library that does not load), the reason and
//! what to do are shown on the display for `kiosk.error_screen_s` seconds,
//! logged, and told to systemd (`STATUS=`), before the process exits with
//! its code. Without it a kiosk that cannot start leaves a black screen
//! with the login prompt already stopped.

use std::path::Path;
use std::time::{Duration, Instant};

use super::exit;
use super::message::{notice, to_output};
use crate::display::config::DisplayConfig;
use crate::display::present::{OutputChoice, PresenterKind};
use crate::display::screen::Screen;
use crate::platform::notify::Notifier;

const TITLE: [u8; 4] = [255, 120, 90, 255];
const TEXT: [u8; 4] = [235, 235, 235, 255];
const HINT: [u8; 4] = [255, 210, 120, 255];

/// Characters a line of the reason holds before it wraps.
const WRAP: usize = 72;

/// What the screen says for exit `code` and `reason`, each line with its
/// colour.
#[must_use]
pub fn lines(code: u8, reason: &str, hold_s: f64) -> Vec<(String, [u8; 4])> {
    let mut out = vec![
        ("marionette cannot start".to_owned(), TITLE),
        (String::new(), TEXT),
    ];
    out.extend(reason.lines().flat_map(wrap).map(|l| (l, TEXT)));
    out.push((String::new(), TEXT));
    let what = match code {
        exit::CONFIG => "Fix the configuration named above, then: systemctl restart marionette",
        exit::DATAERR => {
            "Fix or replace the file named above (motion library, recording), then: systemctl restart marionette"
        }
        _ => "See the log, then: systemctl restart marionette",
    };
    out.push((what.to_owned(), HINT));
    out.push(("The log: journalctl -u marionette".to_owned(), HINT));
    out.push((
        format!("(exit {code}; this screen stays {hold_s:.0} s)"),
        TEXT,
    ));
    out
}

/// `text` cut into lines of at most [`WRAP`] characters, at spaces where
/// it can be.
fn wrap(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let mut word = word.to_owned();
        while word.chars().count() > WRAP {
            if !line.is_empty() {
                out.push(std::mem::take(&mut line));
            }
            let cut: String = word.chars().take(WRAP).collect();
            word = word.chars().skip(WRAP).collect();
            out.push(cut);
        }
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > WRAP {
            out.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(&word);
    }
    if !line.is_empty() {
        out.push(line);
    }
    out
}

/// Show why the kiosk cannot start for `hold` (or until SIGTERM), on the
/// output `display` chooses. Display errors are logged and end it early:
/// the exit code still says what happened.
pub fn show(display: &DisplayConfig, dri: &Path, code: u8, reason: &str, hold: Duration) {
    let notifier = Notifier::from_env();
    let first = reason.lines().next().unwrap_or_default();
    notifier.notify(&format!("STATUS=cannot start (exit {code}): {first}"));
    if hold.is_zero() {
        return;
    }
    crate::platform::signals::install_stop_handler();
    let choice = OutputChoice::from_config(display);
    let kind = PresenterKind::parse(&display.presenter).unwrap_or_default();
    let mut screen = match Screen::open_for_pictures(dri, &choice, kind) {
        Ok(s) => s,
        Err(e) => {
            tracing::warn!(error = %e, "no display to show why the kiosk cannot start on");
            return;
        }
    };
    let (ow, oh) = screen.size();
    let rotation = display.rotation();
    let size = if rotation.degrees() % 180 == 0 {
        (ow, oh)
    } else {
        (oh, ow)
    };
    let img = notice(size, &lines(code, reason, hold.as_secs_f64()));
    if let Err(e) = screen
        .show_image(&to_output(&img, rotation))
        .and_then(|()| screen.wait_flip(Duration::from_millis(500)))
    {
        tracing::warn!(error = %e, "cannot show why the kiosk cannot start");
        return;
    }
    tracing::error!(
        code,
        hold_s = hold.as_secs_f64(),
        "cannot start: the reason is on the display"
    );
    let until = Instant::now() + hold;
    while Instant::now() < until && !crate::platform::signals::stop_requested() {
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_screen_says_what_failed_and_what_to_do() {
        let reason = "/etc/marionette/marionette.toml: character.library: the folder /srv/lib does not exist; set it to a library folder (with library.toml) or leave it empty for the default library";
        let l = lines(exit::CONFIG, reason, 60.0);
        assert_eq!(l[0].0, "marionette cannot start");
        assert!(l.iter().all(|(s, _)| s.chars().count() <= WRAP.max(80)));
        let text: Vec<&str> = l.iter().map(|(s, _)| s.as_str()).collect();
        assert_eq!(
            text[2..text.len() - 4].join(" "),
            reason,
            "the reason, whole"
        );
        assert!(text.iter().any(|s| s.contains("Fix the configuration")));
        assert!(text.iter().any(|s| s.contains("journalctl -u marionette")));
        assert!(text.last().unwrap().contains("exit 78"));
        let l = lines(exit::DATAERR, "library.toml: no clips", 30.0);
        assert!(l.iter().any(|(s, _)| s.contains("motion library")));
        assert!(l.iter().all(|(s, _)| s.chars().count() <= 100));
    }

    #[test]
    fn long_words_are_cut_and_the_notice_has_text_on_it() {
        let word = "x".repeat(200);
        let w = wrap(&word);
        assert_eq!(w.len(), 3);
        assert!(w.iter().all(|l| l.chars().count() <= WRAP));
        let img = notice((1280, 720), &lines(exit::CONFIG, "a reason", 60.0));
        let lit = img
            .rgba
            .chunks(4)
            .filter(|p| p[0] > 200 && p[1] > 200)
            .count();
        assert!(lit > 2000, "{lit} lit pixels");
    }
}

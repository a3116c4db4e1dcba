//! Progress on stderr: one look for every command's bars and spinners.

use indicatif::{ProgressBar, ProgressFinish, ProgressStyle};

/// A bar on stderr over `len` units of work: "PREFIX [███░░░] 42% MSG (elapsed, eta)". Like
/// every bar here it is hidden when stderr is not a terminal, so scripts and tests see only
/// the lines they expect.
pub(super) fn work_bar(prefix: &str, len: u64) -> ProgressBar {
    let style = ProgressStyle::with_template(
        "{prefix} [{bar:30}] {percent:>3}% {msg} ({elapsed}, {guarded_eta})",
    )
    .expect("static template")
    .with_key("guarded_eta", guarded_eta);
    // A bar of unknown length starts at 0 %, not indicatif's 100 % of nothing.
    ProgressBar::new(len.max(1))
        .with_style(style)
        .with_prefix(prefix.to_string())
        .with_finish(ProgressFinish::AndClear)
}

/// "eta 2m", once 5 % of the work is done: before, the rate is the start-up's, and the
/// estimate is noise ("eta …").
fn guarded_eta(state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write) {
    let text = if state.fraction() < 0.05 {
        "eta …".to_string()
    } else {
        format!("eta {:#}", indicatif::HumanDuration(state.eta()))
    };
    let _ = w.write_str(&text);
}

/// A spinner on stderr for a step of unknown length: "⠋ PREFIX: MSG (elapsed)".
pub(super) fn spinner(prefix: &str, msg: &str) -> ProgressBar {
    let style = ProgressStyle::with_template("{spinner} {prefix}: {msg} ({elapsed})")
        .expect("static template");
    // Cleared when dropped: an error line then stands alone.
    let bar = ProgressBar::new_spinner()
        .with_style(style)
        .with_prefix(prefix.to_string())
        .with_finish(ProgressFinish::AndClear)
        .with_message(msg.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

/// Where a step reports its progress: its own bars (a command run alone), or a share of one bar
/// across the steps of a chained command (`nephele tables`).
pub(super) enum Show<'a> {
    /// A spinner while the fraction is unknown, a bar once it is, each named `prefix`.
    Own(&'a str),
    /// `bar`'s positions `span.0 … span.1` (of 1000), its message led by `step`.
    Share {
        bar: &'a ProgressBar,
        span: (u64, u64),
        step: &'a str,
    },
}

impl Show<'_> {
    /// A view of the step's progress, dropped (cleared) when the step ends.
    pub(super) fn start(&self) -> Shown<'_> {
        match self {
            Show::Own(prefix) => Shown::Own {
                prefix,
                bar: std::cell::RefCell::new(None),
            },
            Show::Share { bar, span, step } => Shown::Share {
                bar,
                span: *span,
                step,
            },
        }
    }
}

/// A step's progress being shown ([`Show::start`]).
pub(super) enum Shown<'a> {
    Own {
        prefix: &'a str,
        /// The spinner or the bar now on screen (and whether it is a bar).
        bar: std::cell::RefCell<Option<(ProgressBar, bool)>>,
    },
    Share {
        bar: &'a ProgressBar,
        span: (u64, u64),
        step: &'a str,
    },
}

impl Shown<'_> {
    /// The step at `fraction` (None: unknown), with `msg`.
    pub(super) fn set(&self, fraction: Option<f64>, msg: &str) {
        match self {
            Shown::Own { prefix, bar } => {
                let mut b = bar.borrow_mut();
                let is_bar = fraction.is_some();
                if b.as_ref().is_none_or(|(_, was_bar)| *was_bar != is_bar) {
                    let fresh = if is_bar {
                        work_bar(prefix, 1000)
                    } else {
                        spinner(prefix, "")
                    };
                    *b = Some((fresh, is_bar));
                }
                let (shown, _) = b.as_ref().expect("set just above");
                if let Some(f) = fraction {
                    shown.set_position((1000.0 * f.clamp(0.0, 1.0)) as u64);
                }
                shown.set_message(msg.to_string());
            }
            Shown::Share { bar, span, step } => {
                if let Some(f) = fraction {
                    let at = span.0 as f64 + (span.1 - span.0) as f64 * f.clamp(0.0, 1.0);
                    bar.set_position(at as u64);
                }
                bar.set_message(format!("{step}: {msg}"));
            }
        }
    }
}

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

//! The caustics-bench harness (the `caustics` binary's library): the method registry,
//! `caustics run` (render, measure, score, write results) and the result schema.
//! The harness owns timing, fill counting and scoring so every method is measured
//! the same way (DESIGN "The method contract"). Experiments as data
//! (`bench/experiments/*.json`, [`experiment`]), `caustics reproduce` and `merge`
//! ([`reproduce`], [`summary`], [`plots`], the declared [`figures`]) and the regression gate `caustics compare`
//! ([`compare`]) and the static HTML report ([`report`]) build on `run`.

/// `println!` that never panics when stdout is closed early (`caustics list | head -1`:
/// std's `println!` panics on a broken pipe): [`out!`] with a newline. Used for every
/// line the binary prints.
#[macro_export]
macro_rules! outln {
    () => {
        $crate::out!("\n")
    };
    ($($t:tt)*) => {
        $crate::out!("{}\n", format_args!($($t)*))
    };
}

/// `print!` that never panics on a closed stdout: what a closed pipe cannot take is
/// dropped; any other write error is reported on stderr.
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = write!(std::io::stdout(), $($t)*) {
            if e.kind() != std::io::ErrorKind::BrokenPipe {
                eprintln!("error: writing to stdout: {e}");
            }
        }
    }};
}

/// An error with its causes, each said once: `outer: cause: cause`, as anyhow's `{:#}`
/// writes it, except that a cause whose text the message already holds is not repeated
/// (the library errors write their source into their own message, e.g. "cannot load
/// mesh huge.obj: vertex 1 …", so `{:#}` said every mesh refusal twice).
pub fn error_text(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

pub mod adapters_cmd;
pub mod animate;
pub mod ceilings_cmd;
pub mod cli;
pub mod compare;
pub mod experiment;
pub mod figure_spec;
pub mod figures;
pub mod limits_args;
pub mod machine;
pub mod plots;
pub mod reference_cmd;
pub mod references;
pub mod registry;
pub mod report;
pub mod reproduce;
pub mod result;
pub mod resume;
pub mod roofline;
pub mod run;
pub mod schemas;
pub mod stats;
pub mod summary;

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("cannot load mesh huge.obj: {source}")]
    struct Wrapping {
        source: std::io::Error,
    }

    #[test]
    fn each_cause_is_said_once() {
        let inner = std::io::Error::other("vertex 1: expected coordinates within 1e6 m");
        let e = anyhow::Error::new(Wrapping { source: inner }).context("scene.json");
        assert_eq!(
            format!("{e:#}"),
            "scene.json: cannot load mesh huge.obj: vertex 1: expected coordinates within 1e6 m: vertex 1: expected coordinates within 1e6 m"
        );
        assert_eq!(
            error_text(&e),
            "scene.json: cannot load mesh huge.obj: vertex 1: expected coordinates within 1e6 m"
        );
        let plain = anyhow::anyhow!("outer").context("context");
        assert_eq!(error_text(&plain), format!("{plain:#}"));
    }
}

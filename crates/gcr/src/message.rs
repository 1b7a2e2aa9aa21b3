//! An error as `gcr` prints it (after `error: `) and as Python's `GcrError` says it: the error,
//! then each cause, joined by `: `.

/// The message of `e` and its causes (`source()`), joined by `: `, leaving out a cause whose text
/// the message already ends with: errors that quote their cause in their own message (a file
/// that cannot be read names the OS error) would otherwise say it twice.
pub fn error_message(e: &(dyn std::error::Error + 'static)) -> String {
    let mut out = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !out.ends_with(&text) {
            out = format!("{out}: {text}");
        }
        cause = c.source();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::error_message;

    #[test]
    fn a_cause_quoted_by_its_error_is_said_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let quoted = scene_sampler::SceneError::Io {
            path: "/nowhere".into(),
            source: io,
        };
        assert_eq!(
            error_message(&quoted),
            "/nowhere: cannot read: no such file"
        );
        // a context around it, and a cause the message does not quote: both said
        #[derive(Debug, thiserror::Error)]
        #[error("loading scene `x`")]
        struct Loading(#[source] scene_sampler::SceneError);
        assert_eq!(
            error_message(&Loading(quoted)),
            "loading scene `x`: /nowhere: cannot read: no such file"
        );
    }
}

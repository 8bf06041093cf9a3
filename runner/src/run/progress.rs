//! Progress on the terminal: one line rewritten in place on a TTY, plain lines under CI or
//! when output is redirected.

use std::io::{IsTerminal, Write};

#[derive(Debug, Clone, Copy)]
pub struct Progress {
    live: bool,
}

impl Progress {
    pub fn new() -> Progress {
        let ci = std::env::var_os("CI").is_some();
        Progress { live: std::io::stderr().is_terminal() && !ci }
    }

    /// A transient status: replaced by the next one on a terminal, a line of its own otherwise.
    pub fn status(&self, text: &str) {
        let mut err = std::io::stderr().lock();
        if self.live {
            let _ = write!(err, "\r\x1b[2K{text}");
        } else {
            let _ = writeln!(err, "{text}");
        }
        let _ = err.flush();
    }

    /// A line that stays.
    pub fn line(&self, text: &str) {
        let mut err = std::io::stderr().lock();
        if self.live {
            let _ = write!(err, "\r\x1b[2K");
        }
        let _ = writeln!(err, "{text}");
    }
}

impl Default for Progress {
    fn default() -> Self {
        Self::new()
    }
}

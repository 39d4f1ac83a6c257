//! `--color`: whether the log lines on stderr carry ANSI colour codes.

use std::io::IsTerminal as _;

/// When log lines are coloured.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColorChoice {
    /// When stderr is a terminal (a file or a pipe gets plain text).
    #[default]
    Auto,
    /// Always.
    Always,
    /// Never.
    Never,
}

impl ColorChoice {
    /// Whether to write colour codes to a stream that `is_terminal` says is (or is not) a terminal.
    pub fn ansi(self, is_terminal: bool) -> bool {
        match self {
            Self::Auto => is_terminal,
            Self::Always => true,
            Self::Never => false,
        }
    }

    /// Whether to write colour codes to this process's stderr.
    pub fn ansi_on_stderr(self) -> bool {
        self.ansi(std::io::stderr().is_terminal())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_colours_a_terminal_only_and_the_others_are_fixed() {
        assert!(ColorChoice::Auto.ansi(true));
        assert!(!ColorChoice::Auto.ansi(false), "a log file gets no escape codes");
        assert!(ColorChoice::Always.ansi(false));
        assert!(!ColorChoice::Never.ansi(true));
    }
}

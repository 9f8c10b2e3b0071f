//! Output macros every command uses: stdout writes that return a [`crate::error::CliError`]
//! instead of panicking, and stderr writes that never panic. Declared first in `main.rs`
//! (`#[macro_use]`), so every module sees them.

/// `println!` that returns a [`crate::error::CliError`] from the enclosing function when stdout
/// cannot be written (a closed pipe, a full disk) instead of panicking.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
            .map_err(|e| $crate::error::CliError::io("(standard output)", e))?
    }};
}

/// `print!` that returns a [`crate::error::CliError`] like [`outln!`].
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)
            .map_err(|e| $crate::error::CliError::io("(standard output)", e))?
    }};
}

/// `eprintln!` that never panics: a message that cannot reach stderr is dropped, and control
/// characters in it (from names in the scene) are escaped so they cannot drive the terminal.
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let text = twopass_scene::printable(&format!($($arg)*));
        let _ = writeln!(std::io::stderr().lock(), "{text}");
    }};
}

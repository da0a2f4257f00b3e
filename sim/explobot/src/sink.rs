//! Where the command line writes: standard output, and the default run folder `runs/NAME`.

use std::path::{Path, PathBuf};

/// Writes `text` to standard output. A reader that closed the pipe early (`explobot truth | head`)
/// has all it asked for: that is not an error, and nothing panics.
pub fn print_stdout(text: &str) -> std::io::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => other,
    }
}

/// The default output folder of a scenario: `runs/NAME`.
pub fn default_out_dir(scenario_name: &str) -> PathBuf {
    Path::new("runs").join(scenario_name)
}

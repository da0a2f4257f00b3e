//! The signals that stop Carto, their names and the exit codes they end with.

/// Every signal whose default action ends the process and that a process may catch: each goes
/// through the stop path. Not here: SIGKILL and SIGSTOP (cannot be caught), SIGSEGV, SIGBUS,
/// SIGILL and SIGFPE (faults of Carto itself: signal-hook refuses them; a Rust panic is handled
/// instead), SIGPIPE (ignored by Rust's runtime: a write to a closed socket fails and ends that
/// session only), and the signals whose default is to stop, continue or be ignored.
pub fn stop_signals() -> Vec<i32> {
    use nix::libc;
    let mut sigs = vec![
        libc::SIGTERM,
        libc::SIGINT,
        libc::SIGHUP,
        libc::SIGQUIT,
        libc::SIGUSR1,
        libc::SIGUSR2,
        libc::SIGALRM,
        libc::SIGVTALRM,
        libc::SIGPROF,
        libc::SIGIO,
        libc::SIGXCPU,
        libc::SIGXFSZ,
        libc::SIGSYS,
        libc::SIGTRAP,
        libc::SIGABRT,
    ];
    #[cfg(any(target_os = "linux", target_os = "android"))]
    sigs.extend([libc::SIGPWR, libc::SIGSTKFLT]);
    #[cfg(any(target_os = "linux", target_os = "android"))]
    sigs.extend(libc::SIGRTMIN()..=libc::SIGRTMAX());
    sigs
}

pub fn signal_name(sig: usize) -> String {
    let Ok(n) = i32::try_from(sig) else {
        return sig.to_string();
    };
    #[cfg(any(target_os = "linux", target_os = "android"))]
    if (nix::libc::SIGRTMIN()..=nix::libc::SIGRTMAX()).contains(&n) {
        return format!("SIGRTMIN+{}", n - nix::libc::SIGRTMIN());
    }
    match signal_hook::low_level::signal_name(n) {
        Some(name) => name.to_owned(),
        None => sig.to_string(),
    }
}

/// 0 for the signals that ask for an orderly stop (SIGTERM, SIGINT, SIGHUP), 128 + N for the
/// others, as a shell reports a death by signal N: a supervisor can tell them apart.
pub fn signal_exit_code(sig: usize) -> u8 {
    match i32::try_from(sig) {
        Ok(signal_hook::consts::SIGTERM | signal_hook::consts::SIGINT | signal_hook::consts::SIGHUP) => 0,
        Ok(n) => u8::try_from(128 + n).unwrap_or(u8::MAX),
        Err(_) => u8::MAX,
    }
}

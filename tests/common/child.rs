//! The child-process harness of the hostile tests.

/// Runs case `case` of this test binary in a child process (its test
/// `child_entry`, with `SLL_HOSTILE_CASE` set) under a wall-clock limit and a
/// 4 GiB address-space limit; `configure` may add to the command (a working
/// directory, variables). Fails if the child does not end within `limit` (a
/// hang) or ends with a failure or a signal (an abort); returns its stderr.
pub fn in_child(
    case: &str,
    limit: std::time::Duration,
    dir: &std::path::Path,
    configure: impl FnOnce(&mut std::process::Command),
) -> String {
    use std::process::{Command, Stdio};
    let exe = std::env::current_exe().unwrap();
    let stderr_path = dir.join(format!("{case}.stderr"));
    let stderr = std::fs::File::create(&stderr_path).unwrap();
    let mut command = Command::new(exe);
    command
        .args(["child_entry", "--exact", "--nocapture", "--test-threads=1"])
        .env("SLL_HOSTILE_CASE", case)
        .stdout(Stdio::null())
        .stderr(stderr);
    configure(&mut command);
    #[cfg(unix)]
    unsafe {
        use std::os::unix::process::CommandExt;
        // Bounded memory: an allocation of what a file claims fails here
        // (and must become an fmi2Error, not an abort).
        command.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 4 << 30,
                rlim_max: 4 << 30,
            };
            libc::setrlimit(libc::RLIMIT_AS, &limit);
            Ok(())
        });
    }
    let started = std::time::Instant::now();
    let mut child = command.spawn().unwrap();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > limit {
            child.kill().ok();
            child.wait().ok();
            panic!("case `{case}` still running after {limit:?}: it hangs");
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    let err = std::fs::read_to_string(&stderr_path).unwrap_or_default();
    assert!(
        status.success(),
        "case `{case}` ended with {status}:\n{err}"
    );
    // The child's own summary lines (they start with a count).
    let summary: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    eprintln!(
        "case `{case}`: {:.2} s {}",
        started.elapsed().as_secs_f64(),
        summary.join("; ")
    );
    err
}

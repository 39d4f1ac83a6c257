//! The process's memory as the kernel reports it (`/proc/self/status`, Linux): what the
//! benchmarks print and what `summary.json` records.

/// Resident set size now, MiB (`VmRSS`); `None` where `/proc` is not available.
pub fn resident_mib() -> Option<f64> {
    status_kib("VmRSS:").map(|kib| kib / 1024.0)
}

/// Largest resident set size so far, MiB (`VmHWM`); `None` where `/proc` is not available.
pub fn peak_resident_mib() -> Option<f64> {
    status_kib("VmHWM:").map(|kib| kib / 1024.0)
}

fn status_kib(key: &str) -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_status_kib(&status, key)
}

/// The value in kB of the line starting with `key` in a `/proc/*/status` text.
fn parse_status_kib(status: &str, key: &str) -> Option<f64> {
    status
        .lines()
        .find(|l| l.starts_with(key))
        .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_lines_are_read_in_kib() {
        let status = "Name:\tcatmap\nVmHWM:\t  204800 kB\nVmRSS:\t  102400 kB\n";
        assert_eq!(parse_status_kib(status, "VmRSS:"), Some(102_400.0));
        assert_eq!(parse_status_kib(status, "VmHWM:"), Some(204_800.0));
        assert_eq!(parse_status_kib(status, "VmSwap:"), None);
    }

    #[test]
    fn this_process_has_a_resident_set_on_linux() {
        if cfg!(target_os = "linux") {
            let now = resident_mib().expect("VmRSS");
            let peak = peak_resident_mib().expect("VmHWM");
            assert!(now > 0.0 && peak >= now, "now {now} MiB, peak {peak} MiB");
        }
    }
}

//! What the process uses, read from the operating system: resident memory from
//! `/proc/self/status`, CPU time from `getrusage`. Each probe returns None (or false)
//! where the system does not offer it.

/// A `/proc/self/status` field given in kB (`VmRSS:    2092 kB`), in bytes.
pub fn parse_status_bytes(status: &str, key: &str) -> Option<u64> {
    status.lines().find_map(|line| {
        let (name, rest) = line.split_once(':')?;
        if name.trim() != key {
            return None;
        }
        let mut parts = rest.split_whitespace();
        let value: u64 = parts.next()?.parse().ok()?;
        let scale = match parts.next().map(|u| u.to_ascii_lowercase()) {
            Some(u) if u == "kb" => 1024,
            Some(u) if u == "mb" => 1024 * 1024,
            Some(u) if u == "gb" => 1024 * 1024 * 1024,
            None => 1,
            Some(_) => return None,
        };
        Some(value * scale)
    })
}

/// (VmRSS, VmHWM) of this process in bytes, None where `/proc` is not there.
pub fn memory_now() -> Option<(u64, u64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    Some((
        parse_status_bytes(&status, "VmRSS")?,
        parse_status_bytes(&status, "VmHWM")?,
    ))
}

/// Reset the kernel's peak-RSS mark (VmHWM) to the current RSS. False when not allowed.
pub fn reset_peak_memory() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Give free heap pages back to the system so that RSS before a build is not padded
/// with memory freed by the previous size.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks glibc's own free lists.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// CPU seconds (user + system, all threads) of this process so far, None where unknown.
pub fn cpu_seconds() -> Option<f64> {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: getrusage writes into the zeroed struct we own.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } == 0 {
            let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
            return Some(t(usage.ru_utime) + t(usage.ru_stime));
        }
    }
    None
}

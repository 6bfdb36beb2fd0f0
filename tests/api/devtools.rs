//! Just enough of the Chrome DevTools Protocol to drive a page in headless Chromium: fill
//! and submit a form, then read the page it leads to. Chromium's `--dump-dom` and
//! `--screenshot` only load a URL (a GET), so a sign-in takes this. The protocol runs
//! over `--remote-debugging-pipe` (Chromium reads commands on fd 3 and writes replies on
//! fd 4, each a JSON message ended by a NUL byte), which needs no WebSocket client.

use serde_json::{json, Value};
use std::io::{Read, Write};
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A headless Chromium with one page, attached.
pub struct Browser {
    child: Child,
    to: std::fs::File,
    from: std::fs::File,
    buffer: Vec<u8>,
    next_id: u64,
    session: String,
    deadline: Instant,
}

/// `fd` duplicated at 10 or above (close-on-exec), so that moving it to 3 or 4 in the
/// child is never a no-op that keeps the flag.
fn high(fd: RawFd) -> OwnedFd {
    // SAFETY: fcntl on a valid descriptor; the new descriptor is owned from here on
    let dup = unsafe { libc::fcntl(fd, libc::F_DUPFD_CLOEXEC, 10) };
    assert!(dup >= 10, "fcntl: {}", std::io::Error::last_os_error());
    // SAFETY: `dup` is a fresh descriptor nothing else owns
    unsafe { OwnedFd::from_raw_fd(dup) }
}

/// A pipe: its read end and its write end (close-on-exec).
fn pipe() -> (OwnedFd, OwnedFd) {
    let mut fds = [0; 2];
    // SAFETY: pipe2 fills two descriptors that nothing else owns
    let done = unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) };
    assert_eq!(done, 0, "pipe2: {}", std::io::Error::last_os_error());
    // SAFETY: as above
    unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) }
}

impl Browser {
    /// Start `browser` with `flags` and a fresh profile in `profile`, open `url` in a
    /// new page and attach to it; every later call fails past `timeout` from now.
    pub fn open(
        browser: &Path,
        flags: &[&str],
        profile: &Path,
        url: &str,
        timeout: Duration,
    ) -> Self {
        let (chrome_reads, to) = pipe();
        let (from, chrome_writes) = pipe();
        let (input, output) = (
            high(chrome_reads.as_raw_fd()),
            high(chrome_writes.as_raw_fd()),
        );
        drop((chrome_reads, chrome_writes));
        let (input_fd, output_fd) = (input.as_raw_fd(), output.as_raw_fd());
        let mut command = Command::new(browser);
        command
            .args(flags)
            .arg("--remote-debugging-pipe")
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg("about:blank")
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        // SAFETY: only async-signal-safe calls (dup2) between fork and exec
        unsafe {
            command.pre_exec(move || {
                if libc::dup2(input_fd, 3) < 0 || libc::dup2(output_fd, 4) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let child = command.spawn().expect("Chromium starts");
        drop((input, output));
        let mut browser = Self {
            child,
            to: std::fs::File::from(to),
            from: std::fs::File::from(from),
            buffer: Vec::new(),
            next_id: 0,
            session: String::new(),
            deadline: Instant::now() + timeout,
        };
        let target = browser.call("Target.createTarget", json!({ "url": url }));
        let attached = browser.call(
            "Target.attachToTarget",
            json!({ "targetId": target["targetId"], "flatten": true }),
        );
        browser.session = attached["sessionId"].as_str().unwrap().to_string();
        browser
    }

    /// Send a command (to the page once attached) and wait for its result.
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        self.try_call(method, params)
            .unwrap_or_else(|e| panic!("{method}: {e}"))
    }

    /// [`Browser::call`], with the protocol's error as an `Err` (a page navigating away
    /// has no context to evaluate in for a moment).
    pub fn try_call(&mut self, method: &str, params: Value) -> Result<Value, Value> {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({ "id": id, "method": method, "params": params });
        if !self.session.is_empty() {
            message["sessionId"] = json!(self.session);
        }
        let mut bytes = serde_json::to_vec(&message).unwrap();
        bytes.push(0);
        self.to.write_all(&bytes).expect("Chromium reads its pipe");
        loop {
            while let Some(end) = self.buffer.iter().position(|&b| b == 0) {
                let reply: Value = serde_json::from_slice(&self.buffer[..end]).unwrap();
                self.buffer.drain(..=end);
                if reply["id"] == id {
                    return match reply.get("error") {
                        Some(error) => Err(error.clone()),
                        None => Ok(reply["result"].clone()),
                    };
                }
            }
            self.wait_readable(method);
            let mut chunk = [0u8; 65536];
            let n = self.from.read(&mut chunk).expect("Chromium's pipe");
            assert!(n > 0, "Chromium closed its pipe during {method}");
            self.buffer.extend_from_slice(&chunk[..n]);
        }
    }

    fn wait_readable(&self, method: &str) {
        let left = self.deadline.saturating_duration_since(Instant::now());
        assert!(!left.is_zero(), "Chromium did not answer {method} in time");
        let mut poll = libc::pollfd {
            fd: self.from.as_raw_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: one valid pollfd
        let ready =
            unsafe { libc::poll(&mut poll, 1, left.as_millis().min(i32::MAX as u128) as i32) };
        assert!(ready > 0, "Chromium did not answer {method} in time");
    }

    /// The value of a JavaScript expression in the page (a promise is awaited); null
    /// when it cannot be evaluated (the page is navigating) or throws.
    pub fn eval(&mut self, expression: &str) -> Value {
        let params =
            json!({ "expression": expression, "returnByValue": true, "awaitPromise": true });
        match self.try_call("Runtime.evaluate", params) {
            Ok(result) if result.get("exceptionDetails").is_none() => {
                result["result"]["value"].clone()
            }
            _ => Value::Null,
        }
    }

    /// Evaluate `expression` every 100 ms until it is true.
    pub fn wait_until(&mut self, expression: &str) {
        loop {
            if self.eval(expression) == json!(true) {
                return;
            }
            assert!(
                Instant::now() < self.deadline,
                "never true in Chromium: {expression}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

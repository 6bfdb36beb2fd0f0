//! A throwaway Postgres server per test: `initdb` into a fresh directory under /tmp,
//! trust authentication on loopback, a free port, stopped (fast shutdown) on drop.
//! Debian's `postgresql` package puts the binaries in /usr/lib/postgresql/<v>/bin; as
//! root the server runs as the `postgres` user (initdb refuses root). Without the
//! package [`PgServer::start`] returns why, and the test skips, unless
//! `MPSFSI_REQUIRE_POSTGRES` is set (CI sets it): then it fails.

use crate::helpers::free_port;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

pub struct PgServer {
    dir: PathBuf,
    pub port: u16,
    child: Child,
}

/// The newest `/usr/lib/postgresql/<version>/bin` with an `initdb`.
fn bin_dir() -> Option<PathBuf> {
    let mut dirs: Vec<(u32, PathBuf)> = std::fs::read_dir("/usr/lib/postgresql")
        .ok()?
        .filter_map(|e| {
            let e = e.ok()?;
            let version: u32 = e.file_name().to_str()?.parse().ok()?;
            let bin = e.path().join("bin");
            bin.join("initdb").exists().then_some((version, bin))
        })
        .collect();
    dirs.sort();
    dirs.pop().map(|(_, bin)| bin)
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

/// `program args…`, as the `postgres` user when we are root.
fn as_postgres(root: bool, program: &Path) -> Command {
    if root {
        let mut c = Command::new("runuser");
        c.args(["-u", "postgres", "--"]).arg(program);
        c
    } else {
        Command::new(program)
    }
}

impl PgServer {
    /// A running server, or `None` (with the reason printed) when this machine has no
    /// Postgres and CI does not require one.
    pub async fn start_or_skip(test: &str) -> Option<PgServer> {
        match Self::start().await {
            Ok(server) => Some(server),
            Err(reason) if std::env::var_os("MPSFSI_REQUIRE_POSTGRES").is_none() => {
                eprintln!("SKIPPED {test}: {reason}");
                None
            }
            Err(reason) => panic!("{test}: MPSFSI_REQUIRE_POSTGRES is set but {reason}"),
        }
    }

    async fn start() -> Result<PgServer, String> {
        let bin = bin_dir().ok_or(
            "no Postgres server (Debian's `postgresql` package: /usr/lib/postgresql/<v>/bin)",
        )?;
        let root = is_root();
        let dir = PathBuf::from(format!("/tmp/mpsfsi-pg-{}", uuid::Uuid::new_v4()));
        std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {dir:?}: {e}"))?;
        if root {
            let chown = Command::new("chown")
                .args(["-R", "postgres:postgres"])
                .arg(&dir)
                .status()
                .map_err(|e| format!("chown: {e}"))?;
            if !chown.success() {
                return Err(format!("cannot give {dir:?} to the postgres user"));
            }
        }
        let data = dir.join("data");
        let init = as_postgres(root, &bin.join("initdb"))
            .arg("-D")
            .arg(&data)
            .args(["-U", "postgres", "-A", "trust", "-E", "UTF8", "--no-sync"])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .output()
            .map_err(|e| format!("initdb: {e}"))?;
        if !init.status.success() {
            return Err(format!(
                "initdb failed: {}",
                String::from_utf8_lossy(&init.stderr)
            ));
        }
        let port = free_port();
        let log = std::fs::File::create(dir.join("server.log")).map_err(|e| e.to_string())?;
        let child = as_postgres(root, &bin.join("postgres"))
            .arg("-D")
            .arg(&data)
            .args(["-p", &port.to_string(), "-k"])
            .arg(&dir)
            .args(["-c", "listen_addresses=127.0.0.1", "-c", "fsync=off"])
            .args(["-c", "synchronous_commit=off", "-c", "full_page_writes=off"])
            .args(["-c", "max_connections=300"])
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .map_err(|e| format!("postgres: {e}"))?;
        let server = PgServer { dir, port, child };
        let start = Instant::now();
        loop {
            if sqlx::PgPool::connect(&server.url("postgres")).await.is_ok() {
                return Ok(server);
            }
            if start.elapsed() > Duration::from_secs(30) {
                let log =
                    std::fs::read_to_string(server.dir.join("server.log")).unwrap_or_default();
                return Err(format!(
                    "the server did not accept connections in 30 s: {log}"
                ));
            }
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }

    pub fn url(&self, database: &str) -> String {
        format!("postgres://postgres@127.0.0.1:{}/{database}", self.port)
    }

    /// A new empty database; its URL.
    pub async fn fresh_database(&self) -> String {
        let name = format!("t{}", uuid::Uuid::new_v4().simple());
        let admin = sqlx::PgPool::connect(&self.url("postgres")).await.unwrap();
        sqlx::query(&format!("CREATE DATABASE {name}"))
            .execute(&admin)
            .await
            .unwrap();
        admin.close().await;
        self.url(&name)
    }
}

impl Drop for PgServer {
    fn drop(&mut self) {
        // SIGINT: fast shutdown (the runuser child passes it on to the postmaster)
        let pid = self.child.id().to_string();
        let _ = Command::new("pkill").args(["-INT", "-P", &pid]).status();
        let _ = Command::new("kill").args(["-INT", &pid]).status();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            if let Ok(Some(_)) = self.child.try_wait() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

//! A throwaway PostgreSQL server for the database tests: `initdb` in a
//! temporary directory and `pg_ctl` on a free loopback port, as the
//! `postgres` user when the tests run as root. Stopped and removed on drop.
//! With `VIGIL_TEST_DATABASE_URL` set, the tests use that server instead
//! (those that stop the database then fail: they need a server of their own).

use std::path::PathBuf;
use std::process::Command;

/// The server the tests use.
pub struct Cluster {
    /// `postgres://user@host:port`, without a database.
    pub base_url: String,
    /// Ours to stop and start, or an existing server's.
    own: Option<Own>,
}

struct Own {
    bin: PathBuf,
    dir: PathBuf,
    port: u16,
    as_postgres: bool,
}

impl Cluster {
    /// The server of `VIGIL_TEST_DATABASE_URL`, or a new one, with
    /// PostgreSQL's programs installed first if they are missing (see
    /// `vigil_testenv::postgres_bindir`).
    ///
    /// # Panics
    /// If there is neither, with what to install and why it was not.
    pub fn start() -> Cluster {
        if let Ok(url) = std::env::var("VIGIL_TEST_DATABASE_URL")
            && !url.is_empty()
        {
            let base_url = match url.rfind('/') {
                Some(i) if i > "postgres://".len() => url[..i].to_owned(),
                _ => url,
            };
            return Cluster {
                base_url,
                own: None,
            };
        }
        let bin = vigil_testenv::postgres_bindir();
        let as_postgres = vigil_testenv::is_root();
        let dir = std::env::temp_dir().join(format!("vigil-pg-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("a temporary directory");
        if as_postgres {
            run(Command::new("chown").arg("postgres:").arg(&dir), "chown");
        }
        let own = Own {
            port: free_port(),
            bin,
            dir,
            as_postgres,
        };
        own.pg(
            "initdb",
            &[
                "-D",
                &own.data(),
                "-U",
                "vigil",
                "--auth=trust",
                "-E",
                "UTF8",
                "--no-sync",
            ],
        );
        own.start();
        Cluster {
            base_url: format!("postgres://vigil@127.0.0.1:{}", own.port),
            own: Some(own),
        }
    }

    /// True if the tests may stop and start this server.
    pub fn owned(&self) -> bool {
        self.own.is_some()
    }

    /// Stops the server (fast shutdown: connections are closed).
    pub fn stop(&self) {
        if let Some(own) = &self.own {
            own.pg("pg_ctl", &["-D", &own.data(), "-m", "fast", "-w", "stop"]);
        }
    }

    /// Starts it again, on the same port.
    pub fn restart(&self) {
        if let Some(own) = &self.own {
            own.start();
        }
    }

    /// The URL of database `name`, created now.
    pub async fn database(&self, name: &str) -> String {
        use sqlx::Connection;
        let mut conn = sqlx::PgConnection::connect(&format!("{}/postgres", self.base_url))
            .await
            .expect("connect to the test server");
        sqlx::query(&format!("DROP DATABASE IF EXISTS {name} WITH (FORCE)"))
            .execute(&mut conn)
            .await
            .expect("drop database");
        sqlx::query(&format!("CREATE DATABASE {name}"))
            .execute(&mut conn)
            .await
            .expect("create database");
        let _ = conn.close().await;
        format!("{}/{name}", self.base_url)
    }
}

impl Own {
    fn data(&self) -> String {
        self.dir.join("data").display().to_string()
    }

    fn start(&self) {
        let options = format!(
            "-p {} -k {} -c listen_addresses=127.0.0.1 -c fsync=off -c max_connections=200",
            self.port,
            self.dir.display()
        );
        let log = self.dir.join("server.log").display().to_string();
        self.pg(
            "pg_ctl",
            &[
                "-D",
                &self.data(),
                "-l",
                &log,
                "-o",
                &options,
                "-w",
                "start",
            ],
        );
    }

    /// One of PostgreSQL's programs, as `postgres` when we are root.
    fn command(&self, program: &str) -> Command {
        let exe = self.bin.join(program);
        let mut cmd = if self.as_postgres {
            let mut c = Command::new("runuser");
            c.args(["-u", "postgres", "--"]).arg(&exe);
            c
        } else {
            Command::new(&exe)
        };
        cmd.current_dir(&self.dir);
        cmd
    }

    /// Runs one of PostgreSQL's programs; panics if it fails.
    fn pg(&self, program: &str, args: &[&str]) {
        run(self.command(program).args(args), program);
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        if let Some(own) = &self.own {
            let _ = own
                .command("pg_ctl")
                .args(["-D", &own.data(), "-m", "immediate", "-w", "stop"])
                .output();
            let _ = std::fs::remove_dir_all(&own.dir);
        }
    }
}

fn run(cmd: &mut Command, what: &str) {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("cannot run {what}: {e}"));
    assert!(
        out.status.success(),
        "{what} failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

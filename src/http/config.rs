//! Server configuration: every option has a flag and an environment
//! variable (the flag wins).

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use super::serve::ConnLimits;
use crate::catalog::JobLimits;

/// Log output format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum LogFormat {
    /// Human-readable lines.
    Human,
    /// One JSON object per line.
    Json,
}

/// `vigil-server`'s configuration.
#[derive(Debug, Clone, clap::Parser)]
#[command(
    name = "vigil-server",
    version,
    about = "Serves the Vigil planning API over HTTP"
)]
pub struct Config {
    /// Address to listen on.
    #[arg(long, env = "VIGIL_BIND", default_value = "127.0.0.1:8080")]
    pub bind: SocketAddr,
    /// Directory where registered scenarios are kept (created if missing);
    /// not used with --database-url.
    #[arg(long, env = "VIGIL_DATA_DIR", default_value = "./vigil-data")]
    pub data_dir: PathBuf,
    /// PostgreSQL URL (`postgres://user:password@host:port/database`). When
    /// set, registered scenarios are kept in that database, and every
    /// replica pointed at it serves the same catalogue; the schema is
    /// migrated at start.
    #[arg(long, env = "VIGIL_DATABASE_URL", hide_env_values = true)]
    pub database_url: Option<String>,
    /// Time limit of one call to the database, milliseconds (waiting for a
    /// connection included); past it the request gets 503 with Retry-After.
    /// Keep it well below --request-timeout-ms.
    #[arg(long, env = "VIGIL_DATABASE_TIMEOUT_MS", default_value_t = 2_000)]
    pub database_timeout_ms: u64,
    /// Loads every scenario of this data directory (a file store, as
    /// --data-dir keeps it) into the database of --database-url, then
    /// exits. Scenarios already there are left alone: running it twice
    /// changes nothing.
    #[arg(long, value_name = "DIR", requires = "database_url")]
    pub import_dir: Option<PathBuf>,
    /// When set, every /v1 endpoint requires `Authorization: Bearer <key>`.
    #[arg(long, env = "VIGIL_API_KEY", hide_env_values = true)]
    pub api_key: Option<String>,
    /// Origins allowed by CORS, comma-separated (`*` for any). CORS is off
    /// when empty.
    #[arg(long, env = "VIGIL_CORS_ORIGINS", value_delimiter = ',')]
    pub cors_origins: Vec<String>,
    /// Log format.
    #[arg(long, env = "VIGIL_LOG_FORMAT", value_enum, default_value_t = LogFormat::Human)]
    pub log_format: LogFormat,
    /// Most /v1 requests handled at once; past it, requests are shed at once
    /// with 503 and Retry-After.
    #[arg(long, env = "VIGIL_MAX_IN_FLIGHT", default_value_t = Settings::DEFAULT.max_in_flight)]
    pub max_in_flight: usize,
    /// Time limit of a /v1 request, milliseconds (504 past it).
    #[arg(long, env = "VIGIL_REQUEST_TIMEOUT_MS",
        default_value_t = Settings::DEFAULT.request_timeout.as_millis() as u64)]
    pub request_timeout_ms: u64,
    /// Memory for statistics of scenarios planned inline through /v1/plan,
    /// MiB (least recently used are evicted); with --database-url, as much
    /// again for the registered scenarios this replica uses.
    #[arg(long, env = "VIGIL_CACHE_MB", default_value_t = (Settings::DEFAULT.cache_bytes >> 20) as u64)]
    pub cache_mb: u64,
    /// A connection that has not sent a whole request head within this
    /// many milliseconds (of opening, or of its first byte after idling)
    /// is closed.
    #[arg(long, env = "VIGIL_HEADER_TIMEOUT_MS",
        default_value_t = ConnLimits::DEFAULT.header_timeout.as_millis() as u64)]
    pub header_timeout_ms: u64,
    /// A keep-alive connection idle for this many milliseconds is closed.
    #[arg(long, env = "VIGIL_IDLE_TIMEOUT_MS",
        default_value_t = ConnLimits::DEFAULT.idle_timeout.as_millis() as u64)]
    pub idle_timeout_ms: u64,
    /// Most connections open at once; past it a new connection is closed at
    /// once, and the open ones are served as usual.
    #[arg(long, env = "VIGIL_MAX_CONNECTIONS", default_value_t = ConnLimits::DEFAULT.max_connections)]
    pub max_connections: usize,
    /// A scenario whose precomputation is predicted to take longer than
    /// this many milliseconds is registered as a background job (202), and
    /// refused inline in /v1/plan (422).
    #[arg(long, env = "VIGIL_SYNC_PRECOMPUTE_MS",
        default_value_t = JobLimits::DEFAULT.sync_precompute_ms as u64)]
    pub sync_precompute_ms: u64,
    /// Precomputation jobs running at once.
    #[arg(long, env = "VIGIL_PRECOMPUTE_JOBS", default_value_t = JobLimits::DEFAULT.jobs)]
    pub precompute_jobs: usize,
    /// Precomputation jobs waiting at most; past it a registration that
    /// would be a job gets 503.
    #[arg(long, env = "VIGIL_PRECOMPUTE_QUEUE", default_value_t = JobLimits::DEFAULT.queue)]
    pub precompute_queue: usize,
    /// A plan predicted to take more than this many milliseconds of CPU is
    /// refused with 422 before any work starts (0: no limit).
    #[arg(long, env = "VIGIL_MAX_PLAN_MS", default_value_t = DEFAULT_MAX_PLAN_MS)]
    pub max_plan_ms: u64,
    /// A session without a request for this many seconds is dropped.
    #[arg(long, env = "VIGIL_SESSION_TTL_S", default_value_t = Settings::DEFAULT.session_ttl.as_secs())]
    pub session_ttl_s: u64,
    /// Most sessions held at once; past it the least recently used is
    /// dropped.
    #[arg(long, env = "VIGIL_MAX_SESSIONS", default_value_t = Settings::DEFAULT.max_sessions)]
    pub max_sessions: usize,
    /// With a database: most megabytes of sessions this replica caches (the
    /// sessions themselves are in the database).
    #[arg(long, env = "VIGIL_SESSION_CACHE_MB", default_value_t = (Settings::DEFAULT.session_cache_bytes >> 20) as u64)]
    pub session_cache_mb: u64,
    /// Most megabytes of what sessions' steps keep for their next step
    /// (each session's carry: seen sets and windows) on this replica; past
    /// it the least recently used carry is dropped and its session's next
    /// step starts over.
    #[arg(long, env = "VIGIL_SESSION_CARRY_MB", default_value_t = (Settings::DEFAULT.session_carry_bytes >> 20) as u64)]
    pub session_carry_mb: u64,
    /// Lets the kernel back this process's memory with transparent huge
    /// pages as the system allows. Off by default: the first plans of a
    /// process, and loading a stored precomputation, then wait for each
    /// 2 MiB page to be zeroed (see `vigil::memory`).
    #[arg(long, env = "VIGIL_HUGE_PAGES")]
    pub huge_pages: bool,
}

impl Config {
    /// The database URL, if one is set (an empty one is none).
    pub fn database(&self) -> Option<&str> {
        self.database_url.as_deref().filter(|u| !u.is_empty())
    }

    /// The time limit of one call to the database.
    pub fn database_timeout(&self) -> Duration {
        Duration::from_millis(self.database_timeout_ms.max(1))
    }

    /// The limits on connections.
    pub fn conn_limits(&self) -> ConnLimits {
        ConnLimits {
            header_timeout: Duration::from_millis(self.header_timeout_ms.max(1)),
            idle_timeout: Duration::from_millis(self.idle_timeout_ms.max(1)),
            max_connections: self.max_connections.max(1),
        }
    }
}

/// The settings the router needs.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Required bearer key of /v1 endpoints.
    pub api_key: Option<String>,
    /// CORS origins (empty: CORS off).
    pub cors_origins: Vec<String>,
    /// Concurrency limit of /v1.
    pub max_in_flight: usize,
    /// Time limit of a /v1 request.
    pub request_timeout: Duration,
    /// Memory bound of the inline-scenario cache, bytes.
    pub cache_bytes: usize,
    /// Synchronous precompute budget, milliseconds (predicted).
    pub sync_precompute_ms: f64,
    /// Precomputation jobs running at once.
    pub precompute_jobs: usize,
    /// Precomputation jobs waiting at most.
    pub precompute_queue: usize,
    /// Most predicted CPU milliseconds of one plan (`None`: no limit).
    pub max_plan_ms: Option<f64>,
    /// Idle time to live of a session.
    pub session_ttl: Duration,
    /// Most sessions held at once.
    pub max_sessions: usize,
    /// With a database: most bytes of sessions cached by this replica.
    pub session_cache_bytes: usize,
    /// Most bytes of sessions' carries held by this replica.
    pub session_carry_bytes: usize,
    /// Whether plans of detections predicted under [`INLINE_PLAN_MS`] run
    /// on the async worker that received them instead of on rayon's pool;
    /// `None`: when the pool has one thread (one core), where the hop to it
    /// and back is two thread switches of pure cost. (A first-detections
    /// plan would make that hop for each batch of its parallel searches.)
    pub inline_plans: Option<bool>,
}

/// Plans predicted to take at most this many milliseconds of CPU run on the
/// async worker that received them when the server plans inline
/// ([`Settings::plans_inline`]): long enough for the reference workload
/// (~0.5 ms), short enough that the worker's other connections and a
/// deadline wait little.
pub const INLINE_PLAN_MS: f64 = 5.0;

impl Settings {
    /// Whether short plans run on the async worker that received them
    /// (see [`Settings::inline_plans`]).
    pub fn plans_inline(&self) -> bool {
        self.inline_plans
            .unwrap_or_else(|| rayon::current_num_threads() == 1)
    }

    /// The registry's bounds on precomputation.
    pub fn job_limits(&self) -> JobLimits {
        JobLimits {
            sync_precompute_ms: self.sync_precompute_ms,
            jobs: self.precompute_jobs,
            queue: self.precompute_queue,
        }
    }
}

/// The most predicted CPU milliseconds of one plan by default
/// (`--max-plan-ms`; 0 there means no limit).
pub const DEFAULT_MAX_PLAN_MS: u64 = 2_000;

impl Settings {
    /// The defaults, which `vigil-server`'s flags also start from.
    pub const DEFAULT: Settings = Settings {
        api_key: None,
        cors_origins: Vec::new(),
        max_in_flight: 64,
        request_timeout: Duration::from_secs(30),
        cache_bytes: 512 << 20,
        sync_precompute_ms: JobLimits::DEFAULT.sync_precompute_ms,
        precompute_jobs: JobLimits::DEFAULT.jobs,
        precompute_queue: JobLimits::DEFAULT.queue,
        max_plan_ms: Some(DEFAULT_MAX_PLAN_MS as f64),
        session_ttl: Duration::from_secs(600),
        max_sessions: 10_000,
        session_cache_bytes: 256 << 20,
        session_carry_bytes: 512 << 20,
        inline_plans: None,
    };
}

impl Default for Settings {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl From<&Config> for Settings {
    fn from(c: &Config) -> Self {
        Settings {
            api_key: c.api_key.clone().filter(|k| !k.is_empty()),
            cors_origins: c
                .cors_origins
                .iter()
                .filter(|o| !o.is_empty())
                .cloned()
                .collect(),
            max_in_flight: c.max_in_flight.max(1),
            request_timeout: Duration::from_millis(c.request_timeout_ms.max(1)),
            cache_bytes: usize::try_from(c.cache_mb.saturating_mul(1 << 20)).unwrap_or(usize::MAX),
            sync_precompute_ms: c.sync_precompute_ms as f64,
            precompute_jobs: c.precompute_jobs.max(1),
            precompute_queue: c.precompute_queue,
            max_plan_ms: (c.max_plan_ms > 0).then_some(c.max_plan_ms as f64),
            session_ttl: Duration::from_secs(c.session_ttl_s.max(1)),
            max_sessions: c.max_sessions.max(1),
            session_cache_bytes: usize::try_from(c.session_cache_mb.saturating_mul(1 << 20))
                .unwrap_or(usize::MAX),
            session_carry_bytes: usize::try_from(c.session_carry_mb.saturating_mul(1 << 20))
                .unwrap_or(usize::MAX),
            inline_plans: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::{Config, ConnLimits, Settings};

    /// The flags start from the same defaults as the types they fill.
    #[test]
    fn flag_defaults_are_the_types_defaults() {
        let config = Config::parse_from(["vigil-server"]);
        assert_eq!(Settings::from(&config), Settings::default());
        assert_eq!(config.conn_limits(), ConnLimits::default());
    }
}

//! Worker threads of the CPU-side jobs (the photon tracer, the ambient-scattering table):
//! how many, and starting them without panicking when the system refuses one.

use anyhow::{anyhow, ensure, Context as _, Result};

/// The most worker threads a job takes: more than any machine's cores, and few enough
/// that an operating system can start them all (`--threads 100000` used to abort).
pub const MAX_THREADS: usize = 1024;

/// The worker count for `threads` (0: every available core), refused above
/// [`MAX_THREADS`].
pub fn count(threads: usize) -> Result<usize> {
    ensure!(
        threads <= MAX_THREADS,
        "{threads} worker threads are more than the {MAX_THREADS} a job may start"
    );
    Ok(if threads > 0 {
        threads
    } else {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    })
}

/// Runs `work` on `threads` scoped threads and returns what each returned, in start order.
/// A thread the system cannot start is an error naming `what` (the threads already
/// started finish first), not a panic.
pub fn run<T: Send, F: Fn() -> T + Sync>(threads: usize, what: &str, work: F) -> Result<Vec<T>> {
    std::thread::scope(|s| {
        let mut handles = Vec::with_capacity(threads);
        for k in 0..threads {
            let handle = std::thread::Builder::new()
                .spawn_scoped(s, &work)
                .with_context(|| format!("starting {what} worker thread {} of {threads}", k + 1))?;
            handles.push(handle);
        }
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .map_err(|_| anyhow!("a {what} worker thread panicked"))
            })
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_above_the_limit_are_refused_and_zero_is_every_core() {
        assert!(count(MAX_THREADS + 1).is_err());
        assert_eq!(count(3).unwrap(), 3);
        assert!(count(0).unwrap() >= 1);
    }

    #[test]
    fn every_worker_returns_in_order() {
        let next = std::sync::atomic::AtomicUsize::new(0);
        let got = run(4, "test", || {
            next.fetch_add(1, std::sync::atomic::Ordering::SeqCst)
        })
        .unwrap();
        let mut sorted = got.clone();
        sorted.sort();
        assert_eq!(sorted, vec![0, 1, 2, 3]);
    }
}

//! `vlab cache list|clear|path`: the settled beds kept between runs
//! ([`vlab::experiment::bed::cache`]), and the `--no-cache` flag of the commands
//! that settle a bed.

use anyhow::{Context, Result};
use clap::{Args, Subcommand};

use vlab::experiment::bed::cache::{BedCache, BedSource, PHYSICS_FINGERPRINT};

#[derive(Debug, Clone, Args)]
pub struct CacheArgs {
    #[command(subcommand)]
    pub action: CacheAction,
}

#[derive(Debug, Clone, Subcommand)]
pub enum CacheAction {
    /// List the cached beds: scene, particles, packing, size.
    List,
    /// Remove every cached bed (the next run settles anew).
    Clear,
    /// Print the cache folder (set VLAB_CACHE_DIR to move it).
    Path,
}

/// `--no-cache`, for the commands that settle a bed.
#[derive(Debug, Clone, Copy, Args)]
pub struct NoCacheArg {
    /// Settle the bed anew instead of reading it from the bed cache (and do
    /// not store it there).
    #[arg(long)]
    pub no_cache: bool,
}

impl NoCacheArg {
    /// Where this run's beds come from; a platform without a cache folder
    /// settles every bed, with a note.
    pub fn source(self, note: &mut dyn FnMut(&str)) -> BedSource {
        if self.no_cache {
            return BedSource::Settle;
        }
        match BedCache::user() {
            Ok(cache) => BedSource::Cache(cache),
            Err(e) => {
                note(&format!("warning: {e}; the bed is settled anew"));
                BedSource::Settle
            }
        }
    }
}

pub fn run(a: CacheArgs) -> Result<()> {
    let cache = BedCache::user()?;
    match a.action {
        CacheAction::Path => println!("{}", cache.dir().display()),
        CacheAction::List => {
            let beds = cache.list()?;
            if beds.is_empty() {
                println!("no cached beds in {}", cache.dir().display());
                return Ok(());
            }
            println!("{} cached beds in {}", beds.len(), cache.dir().display());
            let mut total = 0u64;
            for b in &beds {
                total += b.bytes;
                let name = b
                    .path
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default();
                match &b.header {
                    Ok(h) if b.stale => println!(
                        "  {name}  {:<12} stale: settled by other physics code (fingerprint {}, this vlab {PHYSICS_FINGERPRINT}); never read, removed by `vlab cache clear`",
                        h.scene,
                        if h.fingerprint.is_empty() {
                            "none"
                        } else {
                            &h.fingerprint
                        },
                    ),
                    Ok(h) => println!(
                        "  {name}  {:<12} {:>6} particles  packing {:.3}  bed {:.1} mm  settled in {:.1} s wall  {:.1} MiB",
                        h.scene,
                        h.n_particles,
                        h.packing_fraction,
                        1e3 * h.bed_height_m,
                        h.settle_wall_time_s,
                        b.bytes as f64 / (1024.0 * 1024.0)
                    ),
                    Err(why) => println!("  {name}  unreadable: {why} (rebuilt when next needed)"),
                }
            }
            println!("  total {:.1} MiB", total as f64 / (1024.0 * 1024.0));
        }
        CacheAction::Clear => {
            let n = cache
                .clear()
                .with_context(|| format!("clearing {}", cache.dir().display()))?;
            println!("removed {n} cached beds from {}", cache.dir().display());
        }
    }
    Ok(())
}

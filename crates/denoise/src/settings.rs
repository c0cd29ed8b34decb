//! What a denoising costs and how it treats the auxiliary images: Cycles' two Denoising
//! settings, "Quality" and "Prefilter", with Cycles' defaults (high, accurate).

/// OIDN's `quality`: the network's size, hence its time (Cycles' "Quality"). In OIDN 2.5 on
/// the CPU, `high` differs from `balanced` only where it runs a larger network, about twice
/// as slow: the beauty with clean albedo and normal (`cleanAux`) and the prefilters; `fast` has
/// a small network for the beauty only (the prefilters run `balanced`). On the command line
/// (`--denoise-quality`) the first paragraph of each value's comment is its help, in this
/// order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Quality {
    /// The final-frame network.
    ///
    /// `OIDN_QUALITY_HIGH`; the default, as Cycles'.
    #[default]
    High,
    /// OIDN's earlier network (half high's time with the accurate prefilter).
    ///
    /// `OIDN_QUALITY_BALANCED`.
    Balanced,
    /// A small network for the image, for previews.
    ///
    /// `OIDN_QUALITY_FAST`: the beauty's small network, about a third of balanced's time.
    Fast,
}

impl Quality {
    /// The value of OIDN's `quality` parameter.
    pub(crate) fn oidn(self) -> i32 {
        match self {
            Quality::Fast => 4,
            Quality::Balanced => 5,
            Quality::High => 6,
        }
    }

    /// Its name on the command line and in EXR headers.
    pub fn name(self) -> &'static str {
        match self {
            Quality::Fast => "fast",
            Quality::Balanced => "balanced",
            Quality::High => "high",
        }
    }
}

/// How the albedo and normal guide the beauty's filter (Cycles' "Prefilter", with its meaning:
/// `intern/cycles/integrator/denoiser_oidn.cpp`). On the command line (`--denoise-prefilter`)
/// the first paragraph of each value's comment is its help, in this order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Prefilter {
    /// Albedo and normal denoised first.
    ///
    /// Each by a filter of its own, then taken as clean: three filters, the best image (the
    /// default, as Cycles' and OIDN's recommendation).
    #[default]
    Accurate,
    /// Albedo and normal cleaned with the beauty.
    ///
    /// Taken as noisy, cleaned by the beauty's own filter: one filter.
    Fast,
    /// Albedo and normal taken as noise-free.
    ///
    /// `cleanAux`: one filter, for converged guides.
    None,
}

impl Prefilter {
    /// Its name on the command line and in EXR headers.
    pub fn name(self) -> &'static str {
        match self {
            Prefilter::None => "none",
            Prefilter::Fast => "fast",
            Prefilter::Accurate => "accurate",
        }
    }

    /// Whether the beauty's filter is told its guides are noise-free.
    pub(crate) fn clean_aux(self) -> bool {
        !matches!(self, Prefilter::Fast)
    }
}

/// A denoising's settings; the default is Cycles' (quality high, accurate prefilter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Settings {
    /// The network's size.
    pub quality: Quality,
    /// How the guides are cleaned.
    pub prefilter: Prefilter,
}

impl std::fmt::Display for Settings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "quality {}, prefilter {}",
            self.quality.name(),
            self.prefilter.name()
        )
    }
}

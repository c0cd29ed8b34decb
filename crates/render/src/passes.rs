//! The output passes beside the beauty (SPEC §6), named, laid out and typed exactly as Blender
//! 5.0 Cycles writes them, so Blender's compositor and Nuke show the same sockets and layers
//! as for a Cycles render.

/// One output pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
// Not `non_exhaustive`: every crate that matches on it is in this workspace, and a new pass
// should fail to compile wherever it is not handled.
pub enum Pass {
    /// Distance along the view axis of the surface seen through the pixel centre and the lens
    /// centre (not anti-aliased, not blurred): what Defocus and ZDefocus nodes expect.
    Depth,
    /// World position of that same surface.
    Position,
    /// World-space shading normal of the first surface, averaged over the pixel's samples.
    Normal,
    /// Albedo of the first rough surface (specular bounces followed), for denoisers.
    DenoisingAlbedo,
    /// Camera-space normal of that surface (x right, y up, z forward), for denoisers.
    DenoisingNormal,
    /// Light reaching the camera after one diffuse scattering, divided by the diffuse colour.
    DiffuseDirect,
    /// Light after more than one scattering whose first was diffuse, over the diffuse colour.
    DiffuseIndirect,
    /// Diffuse albedo of the first surface.
    DiffuseColor,
    /// As `DiffuseDirect`, for glossy (specular) reflection.
    GlossyDirect,
    /// As `DiffuseIndirect`, for glossy reflection.
    GlossyIndirect,
    /// Glossy albedo of the first surface (directional, Fresnel included).
    GlossyColor,
    /// As `DiffuseDirect`, for transmission (zero until transmissive materials exist).
    TransmissionDirect,
    /// As `DiffuseIndirect`, for transmission.
    TransmissionIndirect,
    /// Transmission albedo of the first surface.
    TransmissionColor,
    /// Emitters (and unlit surfaces) seen directly.
    Emission,
    /// The environment seen directly.
    Environment,
    /// Cryptomatte of glTF node names.
    CryptoObject,
    /// Cryptomatte of material names.
    CryptoMaterial,
    /// The samples each pixel took.
    SampleCount,
    /// Screen-space motion (pixels) of the surface seen through the pixel centre towards the
    /// previous and next frames, as Cycles writes it.
    Vector,
}

/// What a pass holds, which decides how it is stored and merged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassKind {
    /// Colour averaged over samples: half with `--half`.
    Colour,
    /// Data averaged over samples (normals): always float32.
    AveragedData,
    /// One value per pixel, not averaged (depth, position, sample count): float32.
    PixelData,
    /// Cryptomatte rank/coverage pairs: float32 (IDs are float bit patterns).
    Cryptomatte,
}

/// Index of a light pass in [`crate::aov::SampleAov::light`].
pub(crate) const LIGHT_PASSES: [Pass; 11] = [
    Pass::DiffuseDirect,
    Pass::DiffuseIndirect,
    Pass::DiffuseColor,
    Pass::GlossyDirect,
    Pass::GlossyIndirect,
    Pass::GlossyColor,
    Pass::TransmissionDirect,
    Pass::TransmissionIndirect,
    Pass::TransmissionColor,
    Pass::Emission,
    Pass::Environment,
];

impl Pass {
    /// Every pass, in output order.
    pub const ALL: [Pass; 20] = [
        Pass::Depth,
        Pass::Position,
        Pass::Normal,
        Pass::DenoisingAlbedo,
        Pass::DenoisingNormal,
        Pass::DiffuseDirect,
        Pass::DiffuseIndirect,
        Pass::DiffuseColor,
        Pass::GlossyDirect,
        Pass::GlossyIndirect,
        Pass::GlossyColor,
        Pass::TransmissionDirect,
        Pass::TransmissionIndirect,
        Pass::TransmissionColor,
        Pass::Emission,
        Pass::Environment,
        Pass::CryptoObject,
        Pass::CryptoMaterial,
        // Before the sample count, which a window always has and a whole render may not:
        // the layers of both then line up.
        Pass::Vector,
        Pass::SampleCount,
    ];

    /// Blender's name for the pass: the layer name in the EXR and the compositor socket.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Depth => "Depth",
            Pass::Position => "Position",
            Pass::Normal => "Normal",
            Pass::DenoisingAlbedo => "Denoising Albedo",
            Pass::DenoisingNormal => "Denoising Normal",
            Pass::DiffuseDirect => "Diffuse Direct",
            Pass::DiffuseIndirect => "Diffuse Indirect",
            Pass::DiffuseColor => "Diffuse Color",
            Pass::GlossyDirect => "Glossy Direct",
            Pass::GlossyIndirect => "Glossy Indirect",
            Pass::GlossyColor => "Glossy Color",
            Pass::TransmissionDirect => "Transmission Direct",
            Pass::TransmissionIndirect => "Transmission Indirect",
            Pass::TransmissionColor => "Transmission Color",
            Pass::Emission => "Emission",
            Pass::Environment => "Environment",
            Pass::CryptoObject => "CryptoObject",
            Pass::CryptoMaterial => "CryptoMaterial",
            Pass::SampleCount => "Debug Sample Count",
            Pass::Vector => "Vector",
        }
    }

    /// The channels of one layer of the pass, as Blender names them.
    pub fn channels(self) -> &'static [&'static str] {
        match self.kind() {
            PassKind::Colour => &["R", "G", "B"],
            PassKind::Cryptomatte => &["R", "G", "B", "A"],
            _ => match self {
                Pass::Depth => &["Z"],
                Pass::SampleCount => &["X"],
                Pass::Vector => &["X", "Y", "Z", "W"],
                _ => &["X", "Y", "Z"],
            },
        }
    }

    /// How the pass is stored and merged.
    pub fn kind(self) -> PassKind {
        match self {
            Pass::Depth | Pass::Position | Pass::SampleCount | Pass::Vector => PassKind::PixelData,
            Pass::Normal | Pass::DenoisingNormal => PassKind::AveragedData,
            Pass::CryptoObject | Pass::CryptoMaterial => PassKind::Cryptomatte,
            _ => PassKind::Colour,
        }
    }

    /// The pass a name means: Blender's name in any letter case, or the same words joined by
    /// `-` or `_` (`denoising-albedo`); `Z` and `Debug Sample Count` too.
    pub fn parse(s: &str) -> Option<Pass> {
        let key = |t: &str| -> String {
            t.chars()
                .filter(|c| !matches!(c, ' ' | '-' | '_'))
                .flat_map(char::to_lowercase)
                .collect()
        };
        let wanted = key(s);
        match wanted.as_str() {
            "z" => return Some(Pass::Depth),
            "samplecount" | "samples" => return Some(Pass::SampleCount),
            _ => {}
        }
        Pass::ALL.into_iter().find(|p| key(p.name()) == wanted)
    }

    fn bit(self) -> u32 {
        1 << Pass::ALL.iter().position(|&p| p == self).expect("in ALL")
    }
}

/// A set of passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct PassSet(u32);

impl PassSet {
    /// No pass: the beauty alone.
    pub const NONE: PassSet = PassSet(0);

    /// The default of `--passes`: what a compositor needs. Depth, Normal, the denoising
    /// features and both Cryptomattes.
    pub fn compositing() -> PassSet {
        [
            Pass::Depth,
            Pass::Normal,
            Pass::DenoisingAlbedo,
            Pass::DenoisingNormal,
            Pass::CryptoObject,
            Pass::CryptoMaterial,
        ]
        .into_iter()
        .collect()
    }

    /// `--passes all`: the default set, the light passes and Position.
    pub fn all() -> PassSet {
        Pass::ALL
            .into_iter()
            .filter(|&p| p != Pass::SampleCount)
            .collect()
    }

    /// True when the set holds `pass`.
    pub fn contains(self, pass: Pass) -> bool {
        self.0 & pass.bit() != 0
    }

    /// The set with `pass` added.
    pub fn with(self, pass: Pass) -> PassSet {
        PassSet(self.0 | pass.bit())
    }

    /// The set without `pass`.
    pub fn without(self, pass: Pass) -> PassSet {
        PassSet(self.0 & !pass.bit())
    }

    /// The passes, in output order.
    pub fn iter(self) -> impl Iterator<Item = Pass> {
        Pass::ALL.into_iter().filter(move |&p| self.contains(p))
    }

    /// True when no pass is in the set.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// True when some light pass (Diffuse/Glossy/Transmission Direct/Indirect/Color,
    /// Emission, Environment) is in the set.
    pub fn has_light_passes(self) -> bool {
        LIGHT_PASSES.iter().any(|&p| self.contains(p))
    }

    /// True when the set needs anything recorded per sample beyond the beauty (the averaged
    /// passes and Cryptomatte); Depth, Position and the sample count are per pixel.
    pub fn needs_sample_records(self) -> bool {
        self.iter()
            .any(|p| !matches!(p.kind(), PassKind::PixelData) || self.has_light_passes())
    }

    /// Parses a `--passes` list: `default`, `all`, `none`, or comma-separated pass names
    /// ([`Pass::parse`]); `default,Position` adds to the default set.
    pub fn parse(list: &str) -> Result<PassSet, String> {
        let mut set = PassSet::NONE;
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            set = match item.to_ascii_lowercase().as_str() {
                "default" => PassSet(set.0 | PassSet::compositing().0),
                "all" => PassSet(set.0 | PassSet::all().0),
                "none" => set,
                _ => match Pass::parse(item) {
                    Some(p) => set.with(p),
                    None => {
                        return Err(format!(
                            "unknown pass {item:?}; passes are default, all, none, {}",
                            Pass::ALL.map(Pass::name).join(", ")
                        ))
                    }
                },
            };
        }
        Ok(set)
    }
}

impl FromIterator<Pass> for PassSet {
    fn from_iter<I: IntoIterator<Item = Pass>>(iter: I) -> Self {
        iter.into_iter().fold(PassSet::NONE, PassSet::with)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_to_their_pass() {
        for p in Pass::ALL {
            assert_eq!(Pass::parse(p.name()), Some(p), "{p:?}");
            assert_eq!(Pass::parse(&p.name().to_uppercase()), Some(p));
            assert_eq!(Pass::parse(&p.name().replace(' ', "-")), Some(p));
        }
        assert_eq!(Pass::parse("z"), Some(Pass::Depth));
        assert_eq!(Pass::parse("albedo"), None);
    }

    #[test]
    fn lists_parse_into_sets() {
        assert_eq!(PassSet::parse("default").unwrap(), PassSet::compositing());
        assert_eq!(PassSet::parse("none").unwrap(), PassSet::NONE);
        let all = PassSet::parse("all").unwrap();
        assert!(all.contains(Pass::Position) && all.contains(Pass::GlossyIndirect));
        assert!(!all.contains(Pass::SampleCount));
        assert_eq!(all.with(Pass::SampleCount).without(Pass::SampleCount), all);
        let mixed = PassSet::parse("default, Position,debug-sample-count").unwrap();
        assert_eq!(
            mixed.iter().count(),
            PassSet::compositing().iter().count() + 2
        );
        assert!(PassSet::parse("Depth,Albedo")
            .unwrap_err()
            .contains("\"Albedo\""));
        assert!(!PassSet::parse("Depth").unwrap().has_light_passes());
        assert!(!PassSet::parse("Depth,Position")
            .unwrap()
            .needs_sample_records());
        assert!(PassSet::parse("Emission").unwrap().needs_sample_records());
    }

    #[test]
    fn channels_and_kinds_follow_blender() {
        assert_eq!(Pass::Depth.channels(), ["Z"]);
        assert_eq!(Pass::Normal.channels(), ["X", "Y", "Z"]);
        assert_eq!(Pass::DenoisingAlbedo.channels(), ["R", "G", "B"]);
        assert_eq!(Pass::SampleCount.channels(), ["X"]);
        assert_eq!(Pass::CryptoObject.channels(), ["R", "G", "B", "A"]);
        assert_eq!(Pass::Emission.kind(), PassKind::Colour);
        assert_eq!(Pass::DenoisingNormal.kind(), PassKind::AveragedData);
    }
}

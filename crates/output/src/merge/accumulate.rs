//! The pixels of a merge: parts read one at a time, pasted into the output or summed into
//! the window they share, by what each pass holds.

use super::options::MergeError;
use super::plan::{Group, Part, Plan};
use aperture_imageio::{Image, Layer, Placement, SampleType};
use aperture_render::cryptomatte::{CryptoPixel, RANKS};
use aperture_render::film::Window;
use aperture_render::passes::{Pass, PassKind};

/// The layer of the samples each pixel took.
pub(super) const SAMPLE_COUNT_LAYER: &str = "Debug Sample Count";

/// How one layer combines across sample batches of the same pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Rule {
    /// Mean weighted by sample counts (colour and averaged data passes).
    Mean,
    /// A light pass stored divided by the Color pass at this layer index: the products with
    /// it are averaged and divided again by the averaged Color.
    OverColour(usize),
    /// One value per pixel, the same in every batch (Depth, Position): the first batch's.
    First,
    /// The samples each pixel took: added.
    Count,
    /// Rank layer `rank_layer` (two ranks each) of the Cryptomatte family `family`.
    Crypto { family: usize, rank_layer: usize },
}

/// The output's layers (the sample count last) and how each merges.
struct Layout {
    names: Vec<String>,
    channels: Vec<Vec<String>>,
    rules: Vec<Rule>,
    families: usize,
}

impl Layout {
    /// The layout of the first part read; `part` names it in errors.
    fn of(image: &Image, part: &Part) -> Result<Layout, MergeError> {
        let layers: Vec<&Layer> = image
            .layers
            .iter()
            .filter(|l| l.name != SAMPLE_COUNT_LAYER)
            .collect();
        let mut families: Vec<String> = Vec::new();
        let mut rules = Vec::with_capacity(layers.len() + 1);
        for l in &layers {
            let unknown = || MergeError::UnknownChannel {
                path: part.path.clone(),
                channel: l.full_channel_name(&l.channels[0]),
            };
            let rule = match Pass::parse(&l.name) {
                Some(pass) => match pass.kind() {
                    PassKind::PixelData => Rule::First,
                    PassKind::Colour => match colour_of(pass)
                        .and_then(|c| layers.iter().position(|m| m.name == c.name()))
                    {
                        Some(c) => Rule::OverColour(c),
                        None => Rule::Mean,
                    },
                    PassKind::AveragedData => Rule::Mean,
                    PassKind::Cryptomatte => return Err(unknown()),
                },
                None => {
                    let (family, rank_layer) = crypto_layer(&l.name).ok_or_else(unknown)?;
                    let family = match families.iter().position(|f| *f == family) {
                        Some(i) => i,
                        None => {
                            families.push(family);
                            families.len() - 1
                        }
                    };
                    Rule::Crypto { family, rank_layer }
                }
            };
            rules.push(rule);
        }
        rules.push(Rule::Count);
        let mut names: Vec<String> = layers.iter().map(|l| l.name.clone()).collect();
        names.push(SAMPLE_COUNT_LAYER.into());
        let mut channels: Vec<Vec<String>> = layers.iter().map(|l| l.channels.clone()).collect();
        channels.push(vec!["X".into()]);
        Ok(Layout {
            names,
            channels,
            rules,
            families: families.len(),
        })
    }

    fn count_layer(&self) -> usize {
        self.names.len() - 1
    }

    /// Index of each output layer in `image`, checking that the part has the same layers.
    fn indices_in(&self, image: &Image, part: &Part) -> Result<Vec<Option<usize>>, MergeError> {
        let mut out = Vec::with_capacity(self.names.len());
        for (name, channels) in self.names.iter().zip(&self.channels) {
            let found = image.layers.iter().position(|l| l.name == *name);
            match found {
                Some(i) if image.layers[i].channels == *channels => out.push(Some(i)),
                None if name == SAMPLE_COUNT_LAYER => out.push(None),
                _ => {
                    return Err(MergeError::PartChanged {
                        path: part.path.clone(),
                    })
                }
            }
        }
        Ok(out)
    }
}

/// The Color pass a Direct or Indirect light pass is stored divided by.
fn colour_of(pass: Pass) -> Option<Pass> {
    match pass {
        Pass::DiffuseDirect | Pass::DiffuseIndirect => Some(Pass::DiffuseColor),
        Pass::GlossyDirect | Pass::GlossyIndirect => Some(Pass::GlossyColor),
        Pass::TransmissionDirect | Pass::TransmissionIndirect => Some(Pass::TransmissionColor),
        _ => None,
    }
}

/// `CryptoObject01` → (`CryptoObject`, 1).
fn crypto_layer(name: &str) -> Option<(String, usize)> {
    let digits = name.get(name.len().checked_sub(2)?..)?;
    let family = &name[..name.len() - 2];
    let rank_layer: usize = digits.parse().ok()?;
    let pass = Pass::parse(family)?;
    (pass.kind() == PassKind::Cryptomatte && rank_layer < RANKS / 2)
        .then(|| (family.to_string(), rank_layer))
}

/// The output image and the layout it follows.
struct Output {
    image: Image,
    layout: Layout,
    window: Window,
}

impl Output {
    fn new(plan: &Plan, first: &Image, part: &Part) -> Result<Output, MergeError> {
        let layout = Layout::of(first, part)?;
        let w = plan.window;
        let mut image = Image::new(w.width, w.height);
        image.beauty_type = first.beauty_type;
        image.placement = (w != Window::whole(plan.full.0, plan.full.1)).then_some(Placement {
            x: w.x0,
            y: w.y0,
            full_width: plan.full.0,
            full_height: plan.full.1,
        });
        for (name, channels) in layout.names.iter().zip(&layout.channels) {
            let names: Vec<&str> = channels.iter().map(String::as_str).collect();
            let mut layer = Layer::new(name, &names, vec![0.0; w.pixels() * channels.len()]);
            layer.sample_type = first.layer(name).map_or(SampleType::F32, |l| l.sample_type);
            image.layers.push(layer);
        }
        Ok(Output {
            image,
            layout,
            window: w,
        })
    }

    /// Index in the output of pixel `i` (row-major) of `window`.
    fn index(&self, window: Window, i: usize) -> usize {
        let (x, y) = (i % window.width as usize, i / window.width as usize);
        (y + (window.y0 - self.window.y0) as usize) * self.window.width as usize
            + x
            + (window.x0 - self.window.x0) as usize
    }

    /// Copies every pixel of `image` (the part `part`) to its place, bit for bit.
    fn paste(&mut self, image: &Image, part: &Part) -> Result<(), MergeError> {
        let at = self.layout.indices_in(image, part)?;
        let count = self.layout.count_layer();
        for i in 0..part.window.pixels() {
            let o = self.index(part.window, i);
            self.image.rgba[o] = image.rgba[i];
            for (l, src) in at.iter().enumerate() {
                let dst = &mut self.image.layers[l];
                let n = dst.channels.len();
                match src {
                    Some(s) => dst.data[o * n..(o + 1) * n]
                        .copy_from_slice(&image.layers[*s].data[i * n..(i + 1) * n]),
                    None => {
                        debug_assert_eq!(l, count);
                        dst.data[o] = part.spp as f32;
                    }
                }
            }
        }
        self.upgrade_types(image);
        Ok(())
    }

    /// A layer stays half only while every part has it half.
    fn upgrade_types(&mut self, image: &Image) {
        if image.beauty_type == SampleType::F32 {
            self.image.beauty_type = SampleType::F32;
        }
        for layer in &mut self.image.layers {
            if image
                .layer(&layer.name)
                .is_some_and(|l| l.sample_type == SampleType::F32)
            {
                layer.sample_type = SampleType::F32;
            }
        }
    }
}

/// Sums of the sample batches of one window.
struct WindowSums {
    window: Window,
    /// Samples per pixel so far.
    weights: Vec<f64>,
    /// Weighted RGBA.
    beauty: Vec<[f64; 4]>,
    /// Weighted values (products with the Color pass for light passes) of each layer that
    /// is averaged; empty for the others.
    layers: Vec<Vec<f64>>,
    /// Sample counts per Cryptomatte ID, per family.
    crypto: Vec<Vec<CryptoPixel>>,
}

impl WindowSums {
    fn new(layout: &Layout, window: Window) -> WindowSums {
        let n = window.pixels();
        WindowSums {
            window,
            weights: vec![0.0; n],
            beauty: vec![[0.0; 4]; n],
            layers: layout
                .rules
                .iter()
                .zip(&layout.channels)
                .map(|(rule, ch)| match rule {
                    Rule::Mean | Rule::OverColour(_) => vec![0.0; n * ch.len()],
                    _ => Vec::new(),
                })
                .collect(),
            crypto: vec![vec![CryptoPixel::default(); n]; layout.families],
        }
    }

    /// Adds one batch; the first batch also gives the output its per-pixel data passes.
    fn add(
        &mut self,
        image: &Image,
        part: &Part,
        out: &mut Output,
        first: bool,
    ) -> Result<(), MergeError> {
        let at = out.layout.indices_in(image, part)?;
        let count = at[out.layout.count_layer()];
        for i in 0..self.window.pixels() {
            let w = count.map_or(f64::from(part.spp), |c| f64::from(image.layers[c].data[i]));
            self.weights[i] += w;
            for (s, v) in self.beauty[i].iter_mut().zip(image.rgba[i]) {
                *s += w * f64::from(v);
            }
            let o = out.index(self.window, i);
            for (l, rule) in out.layout.rules.iter().enumerate() {
                let Some(src) = at[l] else { continue };
                let src = &image.layers[src];
                let n = src.channels.len();
                let values = &src.data[i * n..(i + 1) * n];
                match *rule {
                    Rule::Mean => {
                        for (s, v) in self.layers[l][i * n..].iter_mut().zip(values) {
                            *s += w * f64::from(*v);
                        }
                    }
                    Rule::OverColour(c) => {
                        let colour = &image.layers[at[c].expect("colour layer")].data;
                        let colour = &colour[i * 3..i * 3 + 3];
                        for ((s, v), k) in
                            self.layers[l][i * n..].iter_mut().zip(values).zip(colour)
                        {
                            *s += w * f64::from(*v) * f64::from(*k);
                        }
                    }
                    Rule::First if first => {
                        out.image.layers[l].data[o * n..(o + 1) * n].copy_from_slice(values);
                    }
                    Rule::Crypto { family, .. } => {
                        for pair in values.chunks_exact(2) {
                            let (id, coverage) = (pair[0].to_bits(), f64::from(pair[1]));
                            if id != 0 && coverage > 0.0 {
                                self.crypto[family][i].add_count(id, samples_of(coverage, w));
                            }
                        }
                    }
                    Rule::First | Rule::Count => {}
                }
            }
        }
        out.upgrade_types(image);
        Ok(())
    }

    /// Means, light passes divided again, ranks re-ranked, counts, into the output.
    fn resolve_into(&self, out: &mut Output) {
        for i in 0..self.window.pixels() {
            let w = self.weights[i];
            let mean = |s: f64| if w > 0.0 { (s / w) as f32 } else { 0.0 };
            let o = out.index(self.window, i);
            out.image.rgba[o] = self.beauty[i].map(mean);
            for (l, rule) in out.layout.rules.iter().enumerate() {
                let dst = &mut out.image.layers[l];
                let n = dst.channels.len();
                let px = &mut dst.data[o * n..(o + 1) * n];
                match *rule {
                    Rule::Mean => {
                        for (d, s) in px.iter_mut().zip(&self.layers[l][i * n..]) {
                            *d = mean(*s);
                        }
                    }
                    Rule::OverColour(c) => {
                        let colour = &self.layers[c][i * 3..i * 3 + 3];
                        for ((d, s), k) in px.iter_mut().zip(&self.layers[l][i * n..]).zip(colour) {
                            *d = if *k != 0.0 { (s / k) as f32 } else { 0.0 };
                        }
                    }
                    Rule::Crypto { family, rank_layer } => {
                        let ranks = self.crypto[family][i].ranked(w);
                        for (k, (id, coverage)) in
                            ranks[2 * rank_layer..2 * rank_layer + 2].iter().enumerate()
                        {
                            px[2 * k] = f32::from_bits(*id);
                            px[2 * k + 1] = *coverage;
                        }
                    }
                    Rule::Count => px[0] = w as f32,
                    Rule::First => {}
                }
            }
        }
    }
}

/// Samples of an ID from its coverage in a part of `samples` samples: a whole number unless
/// the part dropped samples (then coverage was counted against fewer).
fn samples_of(coverage: f64, samples: f64) -> f32 {
    let n = coverage * samples;
    let whole = n.round();
    (if (n - whole).abs() < 1e-3 { whole } else { n }) as f32
}

/// Reads the pixels of `part`, checking they are what its header promised.
fn read(part: &Part) -> Result<Image, MergeError> {
    let image = aperture_imageio::read_exr(&part.path).map_err(|source| MergeError::Read {
        path: part.path.clone(),
        source,
    })?;
    let at = image.placement.map_or((0, 0), |p| (p.x, p.y));
    if (image.width, image.height) != (part.window.width, part.window.height)
        || at != (part.window.x0, part.window.y0)
    {
        return Err(MergeError::PartChanged {
            path: part.path.clone(),
        });
    }
    Ok(image)
}

/// The merged pixels of `plan` (the header is the caller's).
pub(super) fn merge_pixels(plan: &Plan, parts: &[Part]) -> Result<Image, MergeError> {
    let mut out: Option<Output> = None;
    for group in &plan.groups {
        merge_group(plan, group, parts, &mut out)?;
    }
    Ok(out.expect("a plan has a part").image)
}

/// One window: its only part pasted, or its batches summed and resolved.
fn merge_group(
    plan: &Plan,
    group: &Group,
    parts: &[Part],
    out: &mut Option<Output>,
) -> Result<(), MergeError> {
    let mut sums: Option<WindowSums> = None;
    for (k, &i) in group.parts.iter().enumerate() {
        let part = &parts[i];
        let image = read(part)?;
        let output = match out {
            Some(o) => o,
            None => out.insert(Output::new(plan, &image, part)?),
        };
        if group.parts.len() == 1 {
            return output.paste(&image, part);
        }
        let s = sums.get_or_insert_with(|| WindowSums::new(&output.layout, group.window));
        s.add(&image, part, output, k == 0)?;
    }
    if let (Some(s), Some(o)) = (&sums, out.as_mut()) {
        s.resolve_into(o);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crypto_layers_and_light_colours_are_recognised() {
        assert_eq!(
            crypto_layer("CryptoObject02"),
            Some(("CryptoObject".into(), 2))
        );
        assert_eq!(
            crypto_layer("CryptoMaterial00"),
            Some(("CryptoMaterial".into(), 0))
        );
        assert_eq!(crypto_layer("CryptoObject03"), None);
        assert_eq!(crypto_layer("Depth00"), None);
        assert_eq!(crypto_layer("0"), None);
        assert_eq!(colour_of(Pass::GlossyIndirect), Some(Pass::GlossyColor));
        assert_eq!(colour_of(Pass::Emission), None);
    }

    #[test]
    fn coverage_turns_back_into_whole_samples() {
        // 3 of 100 samples: 0.03 is not exact in f32, the count is.
        assert_eq!(samples_of(f64::from(3.0f32 / 100.0), 100.0), 3.0);
        assert_eq!(samples_of(0.5, 3.0), 1.5);
    }
}

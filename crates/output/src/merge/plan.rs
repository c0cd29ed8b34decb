//! What a merge will do, decided from the parts' headers alone, before any pixel is read:
//! which parts belong together, which are pasted and which averaged, and every refusal.

use super::options::{MergeError, MergeOptions};
use crate::header::{region_text, split};
use aperture_imageio::{ChannelSpec, ExrHeader, MetaValue};
use aperture_render::film::Window;
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// The sample count pass: it may be absent from a part (a first batch of a uniform render)
/// and is always in the output.
pub(super) const SAMPLE_COUNT_CHANNEL: &str = "Debug Sample Count.X";

/// Sample index ranges, sorted, disjoint and not touching (`0-64,128-192`).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub(crate) struct SampleRanges(pub Vec<Range<u32>>);

impl SampleRanges {
    /// The union of `ranges`, normalised.
    fn union(ranges: impl IntoIterator<Item = Range<u32>>) -> Self {
        let mut all: Vec<Range<u32>> = ranges.into_iter().filter(|r| r.start < r.end).collect();
        all.sort_by_key(|r| (r.start, r.end));
        let mut out: Vec<Range<u32>> = Vec::with_capacity(all.len());
        for r in all {
            match out.last_mut() {
                Some(last) if r.start <= last.end => last.end = last.end.max(r.end),
                _ => out.push(r),
            }
        }
        Self(out)
    }

    /// Samples per pixel the ranges hold.
    pub fn samples(&self) -> u32 {
        self.0.iter().map(|r| r.end - r.start).sum()
    }

    /// The first sample index.
    pub fn first(&self) -> u32 {
        self.0.first().map_or(0, |r| r.start)
    }

    /// Parses `A-B,C-D`.
    fn parse(s: &str) -> Option<Self> {
        let ranges = s
            .split(',')
            .map(|r| {
                let (a, b) = r.trim().split_once('-')?;
                let (a, b) = (a.parse().ok()?, b.parse().ok()?);
                (a < b).then_some(a..b)
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Self::union(ranges))
    }
}

impl std::fmt::Display for SampleRanges {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let text: Vec<String> = self
            .0
            .iter()
            .map(|r| format!("{}-{}", r.start, r.end))
            .collect();
        f.write_str(&text.join(","))
    }
}

/// One part file, as its header describes it.
pub(super) struct Part {
    pub path: PathBuf,
    pub window: Window,
    /// Size of the whole image.
    pub full: (u32, u32),
    pub scene_hash: String,
    pub options_hash: String,
    /// The pose the scene was rendered in (`stored` when the header does not say).
    pub pose: String,
    /// The sample indices the part holds.
    pub ranges: SampleRanges,
    /// Samples per pixel when the part has no sample count pass.
    pub spp: u32,
    /// Channels, sorted by name, the sample count left out.
    pub channels: Vec<ChannelSpec>,
    /// `(K, N)` of `--tile K/N`.
    pub tile: Option<(u32, u32)>,
    pub metadata: Vec<(String, MetaValue)>,
}

impl Part {
    /// Reads and checks the header of `path`.
    pub fn read(path: &Path) -> Result<Part, MergeError> {
        let header =
            aperture_imageio::read_exr_header(path).map_err(|source| MergeError::Read {
                path: path.to_path_buf(),
                source,
            })?;
        Self::from_header(path, header)
    }

    fn from_header(path: &Path, h: ExrHeader) -> Result<Part, MergeError> {
        let missing = |key| MergeError::NotAPart {
            path: path.to_path_buf(),
            key,
        };
        let bad = |key, value: String, why| MergeError::BadHeader {
            path: path.to_path_buf(),
            key,
            value,
            why,
        };
        let text = |key: &'static str| match h.meta(key) {
            Some(MetaValue::Text(t)) => Ok(t.clone()),
            Some(other) => Err(bad(key, format!("{other:?}"), "must be text")),
            None => Err(missing(key)),
        };
        let int = |key: &'static str| match h.meta(key) {
            Some(MetaValue::Int(i)) => u32::try_from(*i)
                .map(Some)
                .map_err(|_| bad(key, i.to_string(), "must be ≥ 0")),
            Some(other) => Err(bad(key, format!("{other:?}"), "must be an integer")),
            None => Ok(None),
        };
        if matches!(h.meta(crate::denoised::DENOISED), Some(MetaValue::Int(v)) if *v != 0) {
            return Err(MergeError::DenoisedPart {
                path: path.to_path_buf(),
            });
        }
        let scene_hash = text(split::SCENE_HASH)?;
        let options_hash = text(split::OPTIONS_HASH)?;
        let pose = match text(split::POSE) {
            Err(MergeError::NotAPart { .. }) => "stored".to_string(),
            other => other?,
        };
        let spp = int(split::SPP)?.ok_or_else(|| missing(split::SPP))?;
        if spp == 0 {
            return Err(bad(split::SPP, "0".into(), "must be ≥ 1"));
        }
        let offset = int(split::SAMPLE_OFFSET)?.unwrap_or(0);
        let ranges = match h.meta(split::SAMPLE_RANGES) {
            Some(MetaValue::Text(t)) => SampleRanges::parse(t).ok_or_else(|| {
                bad(
                    split::SAMPLE_RANGES,
                    t.clone(),
                    "must be ranges A-B,C-D with A < B",
                )
            })?,
            Some(other) => return Err(bad(split::SAMPLE_RANGES, format!("{other:?}"), "text")),
            None => SampleRanges::union(std::iter::once(offset..offset.saturating_add(spp))),
        };
        let tile = tile_of(&h);
        let (window, full) = window_of(&h);
        let channels = h
            .channels
            .into_iter()
            .filter(|c| c.name != SAMPLE_COUNT_CHANNEL)
            .collect();
        Ok(Part {
            path: path.to_path_buf(),
            window,
            full,
            scene_hash,
            options_hash,
            pose,
            ranges,
            spp,
            channels,
            tile,
            metadata: h.metadata,
        })
    }

    /// The header value under `key`.
    pub fn meta(&self, key: &str) -> Option<&MetaValue> {
        self.metadata.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
}

/// The `--tile K/N` a part's header records, if any.
fn tile_of(h: &ExrHeader) -> Option<(u32, u32)> {
    match h.meta(split::TILE) {
        Some(MetaValue::Text(t)) => t
            .split_once('/')
            .and_then(|(k, n)| Some((k.parse().ok()?, n.parse().ok()?))),
        _ => None,
    }
}

/// The pixels a part holds and the size of the whole image, from its data and display windows.
fn window_of(h: &ExrHeader) -> (Window, (u32, u32)) {
    match h.placement {
        Some(p) => (
            Window {
                x0: p.x,
                y0: p.y,
                width: h.width,
                height: h.height,
            },
            (p.full_width, p.full_height),
        ),
        None => (Window::whole(h.width, h.height), (h.width, h.height)),
    }
}

/// Parts of one data window: pasted when alone, averaged when several (sample batches).
pub(super) struct Group {
    pub window: Window,
    /// Indices into the parts, by first sample index.
    pub parts: Vec<usize>,
    /// The samples the group's parts hold together.
    pub ranges: SampleRanges,
}

/// The checked merge.
pub(super) struct Plan {
    /// Size of the whole image.
    pub full: (u32, u32),
    /// The output's data window: the whole image, or with missing parts allowed, the
    /// bounding box of the parts.
    pub window: Window,
    /// Groups by window, top to bottom, left to right.
    pub groups: Vec<Group>,
    /// The samples every pixel holds (with missing parts allowed: the union).
    pub ranges: SampleRanges,
    /// False when pixels or samples are missing.
    pub complete: bool,
}

impl Plan {
    /// Checks that `parts` belong together and decides the merge; each refusal names a part.
    pub fn new(parts: &[Part], opts: &MergeOptions) -> Result<Plan, MergeError> {
        check_identity(parts)?;
        let groups = groups(parts)?;
        check_disjoint_windows(parts, &groups)?;
        let ranges_complete = check_sample_ranges(parts, &groups, opts)?;
        let full = parts[0].full;
        let covered: u64 = groups.iter().map(|g| g.window.pixels() as u64).sum();
        let pixels_complete = covered == u64::from(full.0) * u64::from(full.1);
        if !pixels_complete && !opts.allow_partial {
            return Err(missing_region(parts, &groups, full));
        }
        let window = if pixels_complete {
            Window::whole(full.0, full.1)
        } else {
            bounding_box(groups.iter().map(|g| g.window))
        };
        let ranges = SampleRanges::union(groups.iter().flat_map(|g| g.ranges.0.iter().cloned()));
        Ok(Plan {
            full,
            window,
            groups,
            ranges,
            complete: pixels_complete && ranges_complete,
        })
    }
}

/// Same scene, same options, same image size, same channels as the first part.
fn check_identity(parts: &[Part]) -> Result<(), MergeError> {
    let r = &parts[0];
    for p in &parts[1..] {
        if p.scene_hash != r.scene_hash {
            return Err(MergeError::OtherScene {
                path: p.path.clone(),
                reference: r.path.clone(),
                found: p.scene_hash.clone(),
                expected: r.scene_hash.clone(),
            });
        }
        if p.pose != r.pose {
            return Err(MergeError::OtherPose {
                path: p.path.clone(),
                reference: r.path.clone(),
                found: p.pose.clone(),
                expected: r.pose.clone(),
            });
        }
        if p.options_hash != r.options_hash || p.full != r.full {
            return Err(MergeError::OtherOptions {
                path: p.path.clone(),
                reference: r.path.clone(),
                found: format!("{} at {}x{}", p.options_hash, p.full.0, p.full.1),
                expected: format!("{} at {}x{}", r.options_hash, r.full.0, r.full.1),
            });
        }
        let names =
            |q: &Part| -> Vec<String> { q.channels.iter().map(|c| c.name.clone()).collect() };
        let (a, b) = (names(r), names(p));
        if a != b {
            let what = match b.iter().find(|c| !a.contains(c)) {
                Some(extra) => format!("has channel {extra}, which is not"),
                None => format!(
                    "lacks channel {}, which is",
                    a.iter()
                        .find(|c| !b.contains(c))
                        .map_or("?", |c| c.as_str())
                ),
            };
            return Err(MergeError::OtherChannels {
                path: p.path.clone(),
                reference: r.path.clone(),
                what: format!("{what} in"),
            });
        }
    }
    Ok(())
}

/// Parts grouped by window, each group's parts by first sample index, with overlapping
/// sample ranges refused.
fn groups(parts: &[Part]) -> Result<Vec<Group>, MergeError> {
    let mut by_window: BTreeMap<(u32, u32, u32, u32), Vec<usize>> = BTreeMap::new();
    for (i, p) in parts.iter().enumerate() {
        let w = p.window;
        by_window
            .entry((w.y0, w.x0, w.height, w.width))
            .or_default()
            .push(i);
    }
    by_window
        .into_values()
        .map(|mut members| {
            members.sort_by_key(|&i| (parts[i].ranges.first(), parts[i].ranges.samples()));
            let window = parts[members[0]].window;
            // Every (range, part) of the window by start: an overlap shows between neighbours
            // (against the range reaching furthest so far).
            let mut all: Vec<(Range<u32>, usize)> = members
                .iter()
                .flat_map(|&i| parts[i].ranges.0.iter().map(move |r| (r.clone(), i)))
                .collect();
            all.sort_by_key(|(r, _)| (r.start, r.end));
            let mut furthest: Option<(Range<u32>, usize)> = None;
            for (r, i) in &all {
                if let Some((f, j)) = &furthest {
                    if r.start < f.end {
                        return Err(MergeError::OverlappingSamples {
                            path: parts[*i].path.clone(),
                            other: parts[*j].path.clone(),
                            range: format!("{}..{}", r.start, r.end).into(),
                            other_range: format!("{}..{}", f.start, f.end).into(),
                            region: region_text(&window),
                        });
                    }
                }
                if furthest.as_ref().is_none_or(|(f, _)| r.end > f.end) {
                    furthest = Some((r.clone(), *i));
                }
            }
            Ok(Group {
                window,
                ranges: SampleRanges::union(all.into_iter().map(|(r, _)| r)),
                parts: members,
            })
        })
        .collect()
}

/// Windows of different groups must not share a pixel.
fn check_disjoint_windows(parts: &[Part], groups: &[Group]) -> Result<(), MergeError> {
    for (a, ga) in groups.iter().enumerate() {
        for gb in &groups[a + 1..] {
            if ga.window.overlaps(&gb.window) {
                let (p, q) = (&parts[gb.parts[0]], &parts[ga.parts[0]]);
                return Err(MergeError::OverlappingRegions {
                    path: p.path.clone(),
                    other: q.path.clone(),
                    region: region_text(&p.window),
                    other_region: region_text(&q.window),
                });
            }
        }
    }
    Ok(())
}

/// Every window must hold the same samples; returns whether they do (with missing parts
/// allowed, a difference is let through).
fn check_sample_ranges(
    parts: &[Part],
    groups: &[Group],
    opts: &MergeOptions,
) -> Result<bool, MergeError> {
    let most = groups
        .iter()
        .max_by_key(|g| g.ranges.samples())
        .expect("at least one part");
    for g in groups {
        if g.ranges != most.ranges {
            if opts.allow_partial {
                return Ok(false);
            }
            return Err(MergeError::MissingSamples {
                path: parts[g.parts[0]].path.clone(),
                region: region_text(&g.window),
                has: g.ranges.to_string().into(),
                other: parts[most.parts[0]].path.clone(),
                other_has: most.ranges.to_string().into(),
            });
        }
    }
    Ok(true)
}

fn bounding_box(windows: impl Iterator<Item = Window>) -> Window {
    let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
    for w in windows {
        let (ex, ey) = w.end();
        (x0, y0, x1, y1) = (x0.min(w.x0), y0.min(w.y0), x1.max(ex), y1.max(ey));
    }
    Window::from_corners(x0, y0, x1, y1).expect("parts hold pixels")
}

/// The refusal for uncovered pixels: the first uncovered rectangle (in reading order), and
/// the missing `--tile K/N` when the parts are tiles.
fn missing_region(parts: &[Part], groups: &[Group], full: (u32, u32)) -> MergeError {
    let windows: Vec<Window> = groups.iter().map(|g| g.window).collect();
    let hole = first_hole(&windows, full).unwrap_or(Window::whole(full.0, full.1));
    let n = parts.iter().find_map(|p| p.tile.map(|t| t.1));
    let tiles = match n {
        Some(n) if parts.iter().all(|p| p.tile.is_some_and(|t| t.1 == n)) => {
            let missing: Vec<String> = (0..n)
                .filter(|&k| !parts.iter().any(|p| p.tile.map(|t| t.0) == Some(k)))
                .map(|k| format!("--tile {k}/{n}"))
                .collect();
            if missing.is_empty() {
                String::new()
            } else {
                format!(" (missing: {})", missing.join(", "))
            }
        }
        _ => String::new(),
    };
    MergeError::MissingRegion {
        region: region_text(&hole),
        tiles,
    }
}

/// The first pixel no window covers, in reading order, grown right and down into the
/// largest uncovered rectangle from there; `None` when every pixel is covered.
pub(super) fn first_hole(windows: &[Window], (w, h): (u32, u32)) -> Option<Window> {
    // Coverage changes only at windows' top and bottom rows.
    let mut rows: Vec<u32> = std::iter::once(0)
        .chain(windows.iter().flat_map(|w| [w.y0, w.end().1]))
        .filter(|&y| y < h)
        .collect();
    rows.sort_unstable();
    rows.dedup();
    for y in rows {
        let mut spans: Vec<(u32, u32)> = windows
            .iter()
            .filter(|win| win.y0 <= y && y < win.end().1)
            .map(|win| (win.x0, win.end().0))
            .collect();
        spans.sort_unstable();
        let mut x = 0;
        for (a, b) in spans.iter().copied().chain(std::iter::once((w, w))) {
            if a > x {
                let x1 = a;
                let y1 = windows
                    .iter()
                    .filter(|win| win.y0 > y && win.x0 < x1 && x < win.end().0)
                    .map(|win| win.y0)
                    .min()
                    .unwrap_or(h);
                return Window::from_corners(x, y, x1, y1);
            }
            x = x.max(b);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_normalise_and_parse() {
        let r = SampleRanges::union([64..128, 0..64, 200..210, 205..220]);
        assert_eq!(r.0, [0..128, 200..220]);
        assert_eq!(r.to_string(), "0-128,200-220");
        assert_eq!(r.samples(), 148);
        assert_eq!(SampleRanges::parse("0-128, 200-220"), Some(r));
        assert_eq!(SampleRanges::parse("5-5"), None);
        assert_eq!(SampleRanges::parse("a-b"), None);
    }

    #[test]
    fn holes_are_found_in_reading_order() {
        let bands: Vec<Window> = (0..4).map(|k| Window::band(k, 4, 10, 8).unwrap()).collect();
        assert_eq!(first_hole(&bands, (10, 8)), None);
        let without_2 = [bands[0], bands[1], bands[3]];
        assert_eq!(first_hole(&without_2, (10, 8)), Some(bands[2]));
        // A grid with the middle right tile missing.
        let tile =
            |x: u32, y: u32| Window::from_corners(x * 5, y * 4, x * 5 + 5, y * 4 + 4).unwrap();
        let grid = [tile(0, 0), tile(1, 0), tile(0, 1)];
        assert_eq!(first_hole(&grid, (10, 8)), Some(tile(1, 1)));
        assert_eq!(
            first_hole(&[], (3, 2)),
            Window::from_corners(0, 0, 3, 2),
            "nothing at all"
        );
    }
}

//! The options of `aperture render` that render a part of a render split across machines
//! (SPEC §8): `--region`, `--tile` and `--sample-offset`.

use aperture_render::Window;

/// Which part of the render this run makes.
#[derive(clap::Args, Debug, Clone, Copy, Default, PartialEq)]
pub struct SplitArgs {
    /// Render only the pixels X0 ≤ x < X1, Y0 ≤ y < Y1 (x right, y down; pbrt's
    /// --pixelbounds). EXR only: the file's data window is the region and its display window
    /// the whole image, and `aperture merge` pastes regions back together.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_region, conflicts_with = "tile")]
    pub region: Option<Window>,
    /// Render band K of N (0-based rows ⌊K·H/N⌋ .. ⌊(K+1)·H/N⌋), as a job array hands out
    /// indices: `--tile $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`, or
    /// `--tile $JOB_COMPLETION_INDEX/N` in a Kubernetes indexed Job. EXR only, as --region.
    #[arg(long, value_name = "K/N", value_parser = parse_tile)]
    pub tile: Option<Tile>,
    /// Render sample indices S .. S+spp−1 of every pixel's sequence (Cycles' sample offset):
    /// batches with offsets 0, 64, 128, … and --spp 64 merge into one 192-sample render.
    /// Not with --noise-threshold (split an adaptive render into tiles instead).
    #[arg(long, value_name = "S", default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..65536))]
    pub sample_offset: u32,
}

/// `--tile K/N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tile {
    /// 0-based band index.
    pub index: u32,
    /// Number of bands.
    pub count: u32,
}

fn parse_region(s: &str) -> Result<Window, String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|c| c.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("expected X0,Y0,X1,Y1 (four whole numbers), got {s:?}: {e}"))?;
    let [x0, y0, x1, y1] = v[..] else {
        return Err(format!("expected X0,Y0,X1,Y1 (four numbers), got {s:?}"));
    };
    Window::from_corners(x0, y0, x1, y1)
        .ok_or_else(|| format!("{s:?} holds no pixel: X0 < X1 and Y0 < Y1 are needed"))
}

fn parse_tile(s: &str) -> Result<Tile, String> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| format!("expected K/N, got {s:?}"))?;
    let num = |t: &str| {
        t.trim()
            .parse::<u32>()
            .map_err(|e| format!("expected K/N (whole numbers), got {s:?}: {e}"))
    };
    let (index, count) = (num(k)?, num(n)?);
    if index >= count {
        return Err(format!(
            "tile {index} of {count} does not exist: K counts from 0 to N−1"
        ));
    }
    Ok(Tile { index, count })
}

/// The part of the image one run renders.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ImagePart {
    /// Its pixels.
    pub window: Window,
    /// `(K, N)` when it is band K of N.
    pub tile: Option<(u32, u32)>,
}

impl SplitArgs {
    /// The part of a `width × height` image to render and its tile, or `None` for the whole
    /// image; an error message for a region outside the image or more bands than rows.
    pub fn window(&self, width: u32, height: u32) -> Result<Option<ImagePart>, String> {
        if let Some(r) = self.region {
            if !r.fits(width, height) {
                let (x1, y1) = r.end();
                return Err(format!(
                    "invalid value '{},{},{x1},{y1}' for '--region': the image is {width}x{height}",
                    r.x0, r.y0
                ));
            }
            return Ok(Some(ImagePart {
                window: r,
                tile: None,
            }));
        }
        match self.tile {
            None => Ok(None),
            Some(Tile { index, count }) => Window::band(index, count, width, height)
                .map(|window| {
                    Some(ImagePart {
                        window,
                        tile: Some((index, count)),
                    })
                })
                .ok_or_else(|| {
                    format!(
                        "invalid value '{index}/{count}' for '--tile': the image has {height} rows, \
                         fewer than {count} bands"
                    )
                }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_and_tiles_parse() {
        assert_eq!(
            parse_region("1, 2,30,40"),
            Ok(Window {
                x0: 1,
                y0: 2,
                width: 29,
                height: 38
            })
        );
        for bad in [
            "1,2,3",
            "1,2,3,4,5",
            "3,0,3,4",
            "0,5,4,2",
            "a,b,c,d",
            "-1,0,2,2",
        ] {
            assert!(parse_region(bad).is_err(), "{bad}");
        }
        assert_eq!(parse_tile("3/4"), Ok(Tile { index: 3, count: 4 }));
        for bad in ["4/4", "0/0", "1", "1/x", "-1/4"] {
            assert!(parse_tile(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn windows_follow_the_image() {
        let tile = |index, count| SplitArgs {
            tile: Some(Tile { index, count }),
            ..SplitArgs::default()
        };
        assert_eq!(SplitArgs::default().window(10, 8), Ok(None));
        let part = tile(1, 4).window(10, 8).unwrap().unwrap();
        assert_eq!(
            (part.window, part.tile),
            (Window::band(1, 4, 10, 8).unwrap(), Some((1, 4)))
        );
        assert!(tile(0, 9).window(10, 8).unwrap_err().contains("8 rows"));
        let region = SplitArgs {
            region: Window::from_corners(5, 0, 11, 8),
            ..SplitArgs::default()
        };
        assert!(region.window(10, 8).unwrap_err().contains("10x8"));
        assert!(region.window(11, 8).is_ok());
    }
}

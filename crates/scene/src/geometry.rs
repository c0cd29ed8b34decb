//! Triangles handed to a loaded document in place of a primitive's stored accessors
//! ([`crate::Edit::MeshGeometry`]): what an application holding the triangles itself (Blender's
//! add-on, from the evaluated mesh) gives without writing them to a file first.

use crate::error::Error;

/// One primitive's geometry: positions, optional normals and texture coordinates (set 0), one
/// each per vertex, and triangles indexing them. Checked when made: every index names a vertex,
/// every position is finite.
#[derive(Clone, PartialEq)]
pub struct Geometry {
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    normals: Option<Vec<[f32; 3]>>,
    uvs: Option<Vec<[f32; 2]>>,
}

impl std::fmt::Debug for Geometry {
    // Counts, not a million numbers: an edit list is printed in messages.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Geometry")
            .field("vertices", &self.positions.len())
            .field("triangles", &self.triangles.len())
            .field("normals", &self.normals.is_some())
            .field("uvs", &self.uvs.is_some())
            .finish()
    }
}

impl Geometry {
    /// Checks and keeps the arrays: `normals` and `uvs` (when given) have one value per
    /// position, positions are finite, indices are below the vertex count. An error names the
    /// array and element (`triangles[7]`, …).
    pub fn new(
        positions: Vec<[f32; 3]>,
        triangles: Vec<[u32; 3]>,
        normals: Option<Vec<[f32; 3]>>,
        uvs: Option<Vec<[f32; 2]>>,
    ) -> Result<Self, Error> {
        let n = positions.len();
        if u32::try_from(n).is_err() {
            return Err(invalid(
                "positions",
                format!("{n} vertices exceed u32 indices"),
            ));
        }
        if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !finite(p)) {
            return Err(Error::NonFinite {
                at: format!("positions[{i}]"),
                value: format!("{p:?}"),
            });
        }
        let len = |name: &str, len: Option<usize>| match len {
            Some(l) if l != n => Err(invalid(name, format!("{l} values for {n} positions"))),
            _ => Ok(()),
        };
        len("normals", normals.as_ref().map(Vec::len))?;
        len("uvs", uvs.as_ref().map(Vec::len))?;
        let outside = triangles
            .iter()
            .position(|t| t.iter().any(|&i| i as usize >= n));
        if let Some(k) = outside {
            return Err(invalid(
                &format!("triangles[{k}]"),
                format!("{:?} names a vertex beyond the {n} positions", triangles[k]),
            ));
        }
        Ok(Self {
            positions,
            triangles,
            normals,
            uvs,
        })
    }

    /// The positions.
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// The triangles (vertex indices).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The normals, one per vertex (`None`: flat, as a primitive without `NORMAL`).
    pub fn normals(&self) -> Option<&[[f32; 3]]> {
        self.normals.as_deref()
    }

    /// The texture coordinates of set 0, one per vertex.
    pub fn uvs(&self) -> Option<&[[f32; 2]]> {
        self.uvs.as_deref()
    }
}

fn finite(p: &[f32; 3]) -> bool {
    p.iter().all(|x| x.is_finite())
}

fn invalid(at: &str, reason: String) -> Error {
    Error::Invalid {
        at: at.to_owned(),
        reason,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_arrays_are_errors_that_name_the_element() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let ok = Geometry::new(p.clone(), vec![[0, 1, 2]], None, Some(vec![[0.0; 2]; 3]));
        assert_eq!(ok.map(|g| g.triangles().len()).ok(), Some(1));
        let cases = [
            (
                Geometry::new(p.clone(), vec![[0, 1, 2], [0, 3, 1]], None, None),
                "triangles[1]",
            ),
            (
                Geometry::new(p.clone(), vec![], Some(vec![[0.0; 3]; 2]), None),
                "normals",
            ),
            (
                Geometry::new(p.clone(), vec![], None, Some(vec![[0.0; 2]; 4])),
                "uvs",
            ),
            (
                Geometry::new(vec![[0.0, f32::NAN, 0.0]], vec![], None, None),
                "positions[0]",
            ),
        ];
        for (result, at) in cases {
            let message = result.expect_err(at).to_string();
            assert!(message.contains(at), "{message} should name {at}");
        }
    }

    #[test]
    fn debug_shows_counts_not_values() {
        let g = Geometry::new(vec![[0.5; 3]; 3], vec![[0, 1, 2]], None, None).unwrap();
        let shown = format!("{g:?}");
        assert!(
            shown.contains("vertices: 3") && !shown.contains("0.5"),
            "{shown}"
        );
    }
}

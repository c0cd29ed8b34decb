//! Whether a mesh encloses a volume: what decides, in Blender's sense of a transmissive object
//! (`--transmission blender`), if its glass refracts or stays a thin sheet.

use std::collections::HashMap;

use crate::types::Mesh;

impl Mesh {
    /// True when the triangles form a closed surface: after welding vertices at equal
    /// positions (exporters split vertices along UV seams and sharp edges), every edge is
    /// shared by an even, non-zero number of triangles. Degenerate triangles (repeated
    /// positions) are ignored. An empty mesh is not closed.
    pub fn is_closed(&self) -> bool {
        let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
        let ids: Vec<u32> = self
            .positions
            .iter()
            .map(|p| {
                // +0 and −0 weld together.
                let key = (*p + glam::Vec3::ZERO).to_array().map(f32::to_bits);
                let next = weld.len() as u32;
                *weld.entry(key).or_insert(next)
            })
            .collect();
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        let mut any = false;
        for tri in &self.indices {
            let Some(v) = tri
                .iter()
                .map(|&i| ids.get(i as usize).copied())
                .collect::<Option<Vec<u32>>>()
            else {
                return false;
            };
            if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
                continue;
            }
            any = true;
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        any && edges.values().all(|&n| n % 2 == 0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn tetrahedron() -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            indices: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            ..Mesh::default()
        }
    }

    #[test]
    fn a_tetrahedron_is_closed_and_a_missing_face_opens_it() {
        let mut m = tetrahedron();
        assert!(m.is_closed());
        m.indices.pop();
        assert!(!m.is_closed());
        assert!(!Mesh::default().is_closed());
    }

    /// Split vertices (as along a UV seam) weld back by position.
    #[test]
    fn split_vertices_weld_by_position() {
        let mut m = tetrahedron();
        m.positions.push(Vec3::Z);
        m.indices[3] = [1, 2, 4];
        assert!(m.is_closed());
        // A single quad (two triangles) is open.
        let quad = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            ..Mesh::default()
        };
        assert!(!quad.is_closed());
    }
}

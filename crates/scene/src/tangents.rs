//! MikkTSpace tangents for normal-mapped triangles whose vertices have no `TANGENT`, as the glTF
//! specification asks and as Blender and the glTF sample viewer compute them.
//!
//! MikkTSpace assigns a tangent to every corner of every triangle; corners that share a vertex
//! may disagree (UV seams, mirrored UVs). Such a vertex is split: the corner gets a copy of the
//! vertex with its own tangent, so the shared vertex never averages two frames.

use crate::types::{Mesh, Scene};
use glam::{Vec2, Vec4};
use rayon::prelude::*;

/// The triangles of one mesh that need generated tangents, as MikkTSpace sees them.
struct Faces<'a> {
    mesh: &'a Mesh,
    /// Triangles (indices into `mesh.indices`) to generate for.
    faces: Vec<usize>,
    /// The UV set the normal map reads.
    uv: &'a [Vec2],
    /// Generated tangent per (face, corner).
    out: Vec<[Vec4; 3]>,
}

impl Faces<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.mesh.indices[self.faces[face]][vert] as usize
    }
}

impl mikktspace::Geometry for Faces<'_> {
    fn num_faces(&self) -> usize {
        self.faces.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.vertex(face, vert)].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        // glTF's v points down the image, MikkTSpace's (Blender's) up: flip so the bitangent
        // points up the image, the +Y of a glTF normal map.
        let uv = self.uv[self.vertex(face, vert)];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.out[face][vert] = Vec4::from_array(tangent);
    }
}

/// The UV set whose directions the material's tangent frame follows, if it needs one: its
/// normal map's, else its clear coat normal map's, else (`KHR_materials_anisotropy`, whose
/// direction is given in tangent space) its anisotropy texture's, or set 0.
pub(crate) fn tangent_uv_set(m: &crate::types::Material) -> Option<u32> {
    if let Some(t) = m.normal_texture {
        return Some(t.tex_coord);
    }
    if let Some(t) = m.clearcoat.and_then(|c| c.normal_texture) {
        return Some(t.tex_coord);
    }
    m.anisotropy.map(|a| a.texture.map_or(0, |t| t.tex_coord))
}

/// Gives every normal-mapped (or anisotropic) triangle of `scene` tangents: vertices with `TANGENT` keep theirs,
/// the others get MikkTSpace tangents. Meshes without normal maps are left untouched (their
/// `tangents` stay empty).
pub fn generate_missing_tangents(scene: &mut Scene) {
    let materials = &scene.materials;
    // Most scenes have no normal map: then no triangle's material is looked at.
    if !materials.iter().any(|m| tangent_uv_set(m).is_some()) {
        return;
    }
    scene.meshes.par_iter_mut().for_each(|mesh| {
        // Triangles that need tangents, grouped by the UV set their normal map reads.
        let mut by_set: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
        for (t, &mid) in mesh.material_ids.iter().enumerate() {
            let Some(set) = materials.get(mid as usize).and_then(tangent_uv_set) else {
                continue;
            };
            let Some(tri) = mesh.indices.get(t) else {
                continue;
            };
            let has = |v: u32| {
                mesh.tangents
                    .get(v as usize)
                    .is_some_and(|t| t.truncate() != glam::Vec3::ZERO)
            };
            if !tri.iter().all(|&v| has(v)) {
                by_set[(set as usize).min(1)].push(t);
            }
        }
        for (set, faces) in by_set.into_iter().enumerate() {
            if faces.is_empty() {
                continue;
            }
            let uv = if set == 0 { &mesh.uv0 } else { &mesh.uv1 };
            // Without UVs there is no tangent space; the renderer then leaves normals unmapped.
            if uv.len() != mesh.positions.len() || mesh.normals.len() != mesh.positions.len() {
                continue;
            }
            let n = faces.len();
            let mut g = Faces {
                mesh,
                faces,
                uv,
                out: vec![[Vec4::ZERO; 3]; n],
            };
            if !mikktspace::generate_tangents(&mut g) {
                continue;
            }
            let Faces { faces, out, .. } = g;
            assign(std::sync::Arc::make_mut(mesh), &faces, &out);
        }
    });
}

/// Writes per-corner tangents into the mesh, splitting vertices whose corners disagree.
fn assign(mesh: &mut Mesh, faces: &[usize], out: &[[Vec4; 3]]) {
    if mesh.tangents.len() != mesh.positions.len() {
        mesh.tangents = vec![Vec4::ZERO; mesh.positions.len()];
    }
    // Tangents generated in this pass, so a vertex already written here is compared, not
    // overwritten; vertices from TANGENT are never touched (they start non-zero but are not
    // in `written`).
    let mut written = vec![false; mesh.positions.len()];
    for (&f, corners) in faces.iter().zip(out) {
        for (k, &t) in corners.iter().enumerate() {
            let v = mesh.indices[f][k] as usize;
            if !written[v] {
                mesh.tangents[v] = t;
                written[v] = true;
            } else if !same(mesh.tangents[v], t) {
                let copy = split_vertex(mesh, v);
                mesh.tangents[copy] = t;
                written.push(true);
                mesh.indices[f][k] = copy as u32;
            }
        }
    }
}

fn same(a: Vec4, b: Vec4) -> bool {
    a.w == b.w && a.truncate().dot(b.truncate()) > 0.9999
}

/// Appends a copy of vertex `v` (every attribute) and returns its index.
fn split_vertex(mesh: &mut Mesh, v: usize) -> usize {
    fn dup<T: Copy>(a: &mut Vec<T>, v: usize) {
        if let Some(&x) = a.get(v) {
            a.push(x);
        }
    }
    dup(&mut mesh.positions, v);
    dup(&mut mesh.normals, v);
    dup(&mut mesh.tangents, v);
    dup(&mut mesh.uv0, v);
    dup(&mut mesh.uv1, v);
    for set in &mut mesh.uv_more {
        dup(set, v);
    }
    dup(&mut mesh.colors, v);
    mesh.positions.len() - 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{Material, TextureRef};
    use glam::Vec3;

    fn normal_mapped() -> Material {
        Material {
            normal_texture: Some(TextureRef {
                texture: 0,
                tex_coord: 0,
                transform: None,
            }),
            ..Material::default()
        }
    }

    /// A quad in the XY plane facing +Z, uv (0,0) at its top-left (glTF: v down the image).
    fn quad(uv_mirrored: bool) -> Mesh {
        let u = |x: f32| if uv_mirrored { 1.0 - x } else { x };
        Mesh {
            positions: vec![
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
            ],
            normals: vec![Vec3::Z; 4],
            uv0: vec![
                Vec2::new(u(0.0), 0.0),
                Vec2::new(u(0.0), 1.0),
                Vec2::new(u(1.0), 1.0),
                Vec2::new(u(1.0), 0.0),
            ],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material_ids: vec![0, 0],
            ..Mesh::default()
        }
    }

    #[test]
    fn tangent_follows_u_and_bitangent_points_up_the_image() {
        for mirrored in [false, true] {
            let mut s = Scene {
                meshes: vec![quad(mirrored).into()],
                materials: vec![normal_mapped()],
                ..Scene::default()
            };
            generate_missing_tangents(&mut s);
            let m = &s.meshes[0];
            assert_eq!(m.tangents.len(), m.positions.len());
            for t in &m.tangents {
                let want = if mirrored { -Vec3::X } else { Vec3::X };
                assert!((t.truncate() - want).length() < 1e-4, "{t}");
                // Bitangent = cross(N, T) · w must point to decreasing v: +Y here.
                let b = Vec3::Z.cross(t.truncate()) * t.w;
                assert!((b - Vec3::Y).length() < 1e-4, "{b}");
            }
        }
    }

    #[test]
    fn given_tangents_are_kept_and_unmapped_meshes_untouched() {
        let mut given = quad(false);
        given.tangents = vec![Vec4::new(0.0, 1.0, 0.0, -1.0); 4];
        let mut s = Scene {
            meshes: vec![given.into(), quad(false).into()],
            materials: vec![normal_mapped(), Material::default()],
            ..Scene::default()
        };
        std::sync::Arc::make_mut(&mut s.meshes[1]).material_ids = vec![1, 1];
        generate_missing_tangents(&mut s);
        assert!(s.meshes[0]
            .tangents
            .iter()
            .all(|&t| t == Vec4::new(0.0, 1.0, 0.0, -1.0)));
        assert!(s.meshes[1].tangents.is_empty());
    }

    #[test]
    fn a_uv_seam_splits_the_shared_vertices() {
        // Moving vertex 3's uv across the shared edge mirrors triangle 1's UV layout: the two
        // triangles have opposite handedness, so the shared corners 0 and 2 cannot share a
        // tangent.
        let mut m = quad(false);
        m.uv0[3] = Vec2::new(-1.0, 0.0);
        let mut s = Scene {
            meshes: vec![m.into()],
            materials: vec![normal_mapped()],
            ..Scene::default()
        };
        generate_missing_tangents(&mut s);
        let m = &s.meshes[0];
        assert_eq!(m.tangents.len(), m.positions.len());
        assert_eq!(m.uv0.len(), m.positions.len());
        assert!(m.positions.len() > 4, "no vertex was split");
        let w = |f: usize| m.tangents[m.indices[f][0] as usize].w;
        assert_eq!(w(0), -w(1));
        // Every corner's tangent is unit length and orthogonal to the normal.
        for tri in &m.indices {
            for &v in tri {
                let t = m.tangents[v as usize];
                assert!((t.truncate().length() - 1.0).abs() < 1e-4);
                assert!(t.truncate().dot(Vec3::Z).abs() < 1e-4);
            }
        }
    }
}

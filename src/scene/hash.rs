//! The scene's hash ([`super::Scene::hash`]): every float of what determines the image by its
//! bits (geometry, materials, camera, environment), extended for scenes with textures by their
//! texture coordinates, maps and texels.

use super::Mesh;
use crate::bsdf::Specular;
use crate::camera::CameraDesc;
use crate::environment::Environment;
use crate::material::Material;
use crate::math::WordHash;
use crate::texture::TextureSet;
use glam::Vec3;

/// Hash of the scene's content, in input order: every float by its bits.
pub(super) fn content_hash(
    mesh: &Mesh,
    materials: &[Material],
    camera: &CameraDesc,
    env: &Environment,
) -> u64 {
    fn put(words: &mut WordHash, vs: &[Vec3]) {
        for v in vs {
            words.extend(v.to_array().map(|x| x.to_bits() as u64));
        }
    }
    // streamed (the same value as hash_words of all the words: a buffer of them took 160 bytes
    // per triangle, a third of the peak memory of loading a million)
    let mut w = WordHash::default();
    for t in &mesh.triangles {
        put(&mut w, &t.p);
        if let Some(n) = &t.normals {
            put(&mut w, n);
        }
        w.push(t.material as u64);
    }
    for m in materials {
        put(&mut w, &[m.kd(), m.ks(), m.emission]);
        w.push(m.exponent().to_bits() as u64);
        // a delta lobe's words only where there is one: the hash of a scene without stays
        match m.specular {
            None => {}
            Some(Specular::Mirror {
                reflectance,
                schlick,
            }) => {
                w.push(0x4d49_5252_4f52 | (schlick as u64) << 48); // "MIRROR"
                put(&mut w, &[reflectance]);
            }
            Some(Specular::Dielectric { ior, transmittance }) => {
                w.extend([0x0047_4c41_5353, ior.to_bits() as u64]); // "GLASS"
                put(&mut w, &[transmittance]);
            }
        }
    }
    put(&mut w, &[camera.eye, camera.target, camera.up]);
    // a constant environment's three words stand where they always stood: old hashes hold
    w.extend(env.hash_words());
    w.push(camera.fov_deg.to_bits() as u64);
    w.finish()
}

/// `hash` extended by what textures add to the image: every triangle's texture coordinates,
/// the materials' maps, and the texels (only for scenes with textures, so the hash of a scene
/// without them is what it always was).
pub(super) fn texture_hash(
    hash: u64,
    mesh: &Mesh,
    materials: &[Material],
    textures: &TextureSet,
) -> u64 {
    // streamed: a buffer of the words took 32 bytes per texel
    let mut w = WordHash::default();
    w.push(hash);
    let f = |x: f32| x.to_bits() as u64;
    for t in &mesh.triangles {
        if let Some(uv) = &t.uvs {
            w.extend(uv.iter().flat_map(|v| [f(v.x), f(v.y)]));
        }
    }
    for m in materials {
        let maps = &m.maps;
        let refs = [
            maps.kd,
            maps.ks,
            maps.ns,
            maps.opacity,
            maps.normal,
            maps.bump.map(|b| b.0),
        ];
        for r in refs {
            match r {
                Some(r) => w.extend([
                    r.index as u64,
                    f(r.scale.x),
                    f(r.scale.y),
                    f(r.offset.x),
                    f(r.offset.y),
                ]),
                None => w.push(u64::MAX),
            }
        }
        w.push(maps.bump.map_or(0, |b| f(b.1)));
    }
    for t in &textures.textures {
        let (tw, th) = t.size();
        w.extend([tw as u64, th as u64]);
        for y in 0..th as i64 {
            for x in 0..tw as i64 {
                w.extend(t.texel(x, y).to_array().map(f));
            }
        }
    }
    w.finish()
}

//! Why a render came out black: a mean luminance below [`BLACK_LUMINANCE`], and the one line
//! `vrpt render` then prints, saying what in the scene would light the image.

use crate::scene::Scene;

/// The mean luminance below which an image is black or nearly so: a thousandth of a white
/// diffuse surface under a white sky; its PNG's pixels are at most 3 of 255.
pub const BLACK_LUMINANCE: f64 = 1e-3;

/// Why the image of `film` is black or nearly so (its mean luminance below
/// [`BLACK_LUMINANCE`]), in one line that says what would light it; `None` for an image that is
/// not.
pub fn why_black(scene: &Scene, film: &crate::film::Film) -> Option<String> {
    let n = film.len().max(1) as f64;
    let mean = (0..film.len())
        .map(|i| crate::math::luminance(film.mean(i).as_vec3()) as f64)
        .sum::<f64>()
        / n;
    if mean >= BLACK_LUMINANCE {
        return None;
    }
    let lights = &scene.lights;
    let environment = lights.environment.luminance_integral();
    let why = match (lights.emitters.len(), environment > 0.0) {
        (0, false) => "the scene has no emitter and its environment is black".to_string(),
        (n, false) => {
            let power: f32 = lights.emitters.iter().map(|e| e.power()).sum();
            format!(
                "no emitter's light reached the camera: the environment is black and the \
                 scene's {n} emitters (total power {power:.3}) light nothing it sees"
            )
        }
        (_, true) => "little light reaches what the camera sees".to_string(),
    };
    Some(format!(
        "the image is black (mean luminance {mean:.1e}): {why}; `[environment] radiance = \
         [1, 1, 1]` in scene.toml lights it from outside, a `[camera]` block (eye, target, up, \
         fov) looks elsewhere, --exposure brightens the PNG"
    ))
}

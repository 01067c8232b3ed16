//! [`LightSampler`]: a light chosen (by a [`Choice`]: uniform, power or the tree) and a point on
//! it (area, solid angle or projected), with the pdf per solid angle of any direction (see the
//! [module above](super)).

use super::*;

/// How the lights are sampled in one render: the points method and the chooser.
#[derive(Clone, Copy, Debug)]
pub struct LightSampler<'a> {
    pub(super) lights: &'a Lights,
    pub(super) points: LightPoints,
    pub(super) choice: Choice<'a>,
}

/// A chosen light: emitter `i`, or the environment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Chosen {
    Emitter(u32),
    Environment,
}

impl LightSampler<'_> {
    /// True when something can be sampled.
    pub fn any(&self) -> bool {
        self.lights.any()
    }

    /// Whether the light [`LightSampler::choose`] picks depends on its `u`: not where one light
    /// has power and the chooser is a table (which passes over the lights of no power) or a
    /// tree of one emitter (its one leaf takes the emitters' units, the environment none or
    /// all). A path then skips the light-choice value, not drawn (`BounceSample::draw_needed`).
    pub fn chooses(&self) -> bool {
        !(self.lights.one
            && (matches!(self.choice, Choice::Table(_)) || self.lights.emitters.len() == 1))
    }

    /// The light chosen by `u` for a receiver at `p` with normal `n`, and its probability
    /// (exactly the frequency of this choice from `p`). `None`: nothing to choose from here.
    #[inline]
    pub fn choose(&self, p: Vec3, n: Vec3, u: f32) -> Option<(Chosen, f32)> {
        self.choice.choose(p, n, u)
    }

    /// The probability that [`LightSampler::choose`] picks emitter `i` for `(p, n)`.
    #[inline]
    pub fn pmf(&self, p: Vec3, n: Vec3, i: u32) -> f32 {
        self.choice.pmf(p, n, i)
    }

    /// The probability of choosing the environment.
    #[inline]
    pub fn environment_pmf(&self) -> f32 {
        self.choice.environment_pmf()
    }

    /// Sample a light for the point `p` with shading normal `n` (on the side light is gathered
    /// from): `u_choose` picks the light, `u` the point on it (or the environment direction).
    /// `None` when nothing is sampled or the point sees the back of the chosen emitter.
    #[inline]
    pub fn sample(&self, p: Vec3, n: Vec3, u_choose: f32, u: Vec2) -> Option<LightSample> {
        let (chosen, pmf) = self.choose(p, n, u_choose)?;
        match chosen {
            Chosen::Emitter(i) => {
                let e = &self.lights.emitters[i as usize];
                let (y, pdf) = self.point_on(e, p, n, u)?;
                let d = y - p;
                let dist = d.length();
                if dist <= 0.0 || pdf.is_nan() || pdf <= 0.0 || !pdf.is_finite() {
                    return None;
                }
                Some(LightSample {
                    wi: d / dist,
                    dist,
                    le: e.emission,
                    pdf: pmf * pdf,
                })
            }
            Chosen::Environment => {
                if let Some(m) = self.map_sampled() {
                    let (wi, le, pdf) = m.sample(u)?;
                    return Some(LightSample {
                        wi,
                        dist: f32::INFINITY,
                        le,
                        pdf: pmf * pdf,
                    });
                }
                let local = sample_cosine_hemisphere(u);
                let pdf = pmf * cosine_hemisphere_pdf(local.z);
                let wi = Frame::from_normal(n).to_world(local);
                (pdf > 0.0).then(|| LightSample {
                    wi,
                    dist: f32::INFINITY,
                    le: self.lights.environment.radiance(wi),
                    pdf,
                })
            }
        }
    }

    /// A point on emitter `e` seen from `p` (normal `n`) at `u`, and its pdf per solid angle
    /// (without the choice). `None` when `p` sees the emitter's back.
    #[inline]
    fn point_on(&self, e: &Emitter, p: Vec3, n: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
        let (corner, _) = e.corners();
        if e.n.dot(p - corner[0]) <= 0.0 {
            return None; // behind the emitting side (or on its plane)
        }
        let Some(sph) = self.spherical(e, p) else {
            let y = e.point_by_area(u);
            return Some((y, area_pdf(e, p, y)));
        };
        let (u, warp) = if self.points != LightPoints::SolidAngle {
            let w = sph.weights(e, p, n);
            let v = sample_bilinear(u, w);
            (v, bilinear_pdf(v, w))
        } else {
            (u, 1.0)
        };
        let y = match &sph {
            Spherical::Triangle(t) => {
                let w = t.sample(u);
                let den = e.n.dot(w);
                if den >= 0.0 {
                    return None;
                }
                p + w * (e.n.dot(corner[0] - p) / den)
            }
            Spherical::Rectangle(r) => r.sample(u),
        };
        Some((y, warp / sph.area()))
    }

    /// The pdf per solid angle with which [`LightSampler::sample`] at `p` (normal `n`) returns
    /// the point `y` of emitter `i` (0 when `p` sees its back).
    #[inline]
    pub fn pdf(&self, i: u32, p: Vec3, n: Vec3, y: Vec3) -> f32 {
        let e = &self.lights.emitters[i as usize];
        let (corner, _) = e.corners();
        if e.n.dot(p - corner[0]) <= 0.0 {
            return 0.0;
        }
        let pmf = self.pmf(p, n, i);
        if pmf == 0.0 {
            return 0.0;
        }
        let Some(sph) = self.spherical(e, p) else {
            return pmf * area_pdf(e, p, y);
        };
        let warp = if self.points != LightPoints::SolidAngle {
            let u = match &sph {
                Spherical::Triangle(t) => t.invert((y - p).normalize_or_zero()),
                Spherical::Rectangle(r) => r.invert(y),
            };
            // the bilinear density at the domain point the spherical map took (the warped u)
            bilinear_pdf(u, sph.weights(e, p, n))
        } else {
            1.0
        };
        pmf * warp / sph.area()
    }

    /// The pdf per solid angle with which [`LightSampler::sample`] at a point `p` of shading
    /// normal `n` returns the environment direction `wi`.
    #[inline]
    pub fn environment_pdf(&self, n: Vec3, wi: Vec3) -> f32 {
        match self.map_sampled() {
            Some(m) => self.environment_pmf() * m.pdf(wi),
            None => self.environment_pmf() * cosine_hemisphere_pdf(n.dot(wi)),
        }
    }

    /// The spherical domain in which a point on `e` is placed from `p`, or `None` to place it
    /// by area: the one decision [`LightSampler::point_on`] and [`LightSampler::pdf`] share.
    #[inline]
    fn spherical(&self, e: &Emitter, p: Vec3) -> Option<Spherical> {
        match self.points {
            LightPoints::Area => None,
            LightPoints::Auto => {
                let d = e.centre() - p;
                let d2 = d.length_squared();
                let looks = e.area * (-e.n.dot(d)).max(0.0) / (d2 * d2.sqrt());
                if looks >= AUTO_SOLID_ANGLE {
                    Spherical::of(e, p)
                } else {
                    None
                }
            }
            LightPoints::SolidAngle | LightPoints::Projected => Spherical::of(e, p),
        }
    }

    /// The environment map, when it is sampled by its luminance (a map, and light points other
    /// than `area`); `None` when the environment is sampled by the cosine.
    #[inline]
    fn map_sampled(&self) -> Option<&EnvMap> {
        match self.points {
            LightPoints::Area => None,
            _ => self.lights.environment.map(),
        }
    }
}

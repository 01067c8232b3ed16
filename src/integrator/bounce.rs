//! The bounce's direction at a vertex: the BSDF's own strategy, or with a guide one-sample MIS
//! of the guide (probability `α`) and the BSDF, the sample weighted by the mixture pdf
//! `α·p_guide + (1 − α)·p_bsdf` ([`crate::guiding`]). Directions are world, `wo` points back
//! along the arriving ray, pdfs are per unit solid angle.

use super::{Mixture, Path, Vertex};
use crate::bsdf::{Bsdf, BsdfSample};
use crate::guiding::{canonical_to_dir, dir_to_canonical, GuideAt};
use crate::sampler::layout::BounceSample;
use glam::Vec3;

impl Path<'_> {
    /// The bounce's direction (world), its sample (local, with the pdf the estimator divides
    /// by), and with a guide the [`Mixture`] it was drawn from; `None` ends the path (a failed
    /// sample). With a guide: one-sample MIS of the guide (probability `α`) and the BSDF,
    /// weighted by the mixture pdf `α·p_guide + (1 − α)·p_bsdf`.
    #[inline(always)]
    pub(super) fn sample_direction(
        &self,
        v: &Vertex,
        bsdf: &Bsdf,
        g: Option<&GuideAt>,
        u: &BounceSample,
    ) -> Option<(Vec3, BsdfSample, Option<Mixture>)> {
        let directions = self.settings.directions;
        let Some(g) = g else {
            let bs = bsdf.sample(v.wo_local, u.lobe, u.direction, directions)?;
            return Some((v.frame.to_world(bs.wi), bs, None));
        };
        let (wi, c, wi_local, f, p_bsdf, p_guide) = if u.guide < g.alpha {
            // the density comes from the descent that drew the point
            let (c, p_guide) = g.sample(u.guided_direction);
            let wi = canonical_to_dir(c);
            let wi_local = v.frame.to_local(wi);
            if wi_local.z <= 0.0 {
                return None; // a guided direction below the surface: a failed sample
            }
            let p_bsdf = bsdf.pdf(v.wo_local, wi_local, directions);
            let f = bsdf.eval(v.wo_local, wi_local);
            (wi, c, wi_local, f, p_bsdf, p_guide)
        } else {
            let bs = bsdf.sample(v.wo_local, u.lobe, u.direction, directions)?;
            let wi = v.frame.to_world(bs.wi);
            let c = dir_to_canonical(wi);
            (wi, c, bs.wi, bs.f, bs.pdf, g.guide_pdf_canonical(c))
        };
        let pdf = g.mixture(p_guide, p_bsdf);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let bs = BsdfSample {
            wi: wi_local,
            f,
            pdf,
        };
        let mix = Mixture {
            point: c,
            p_bsdf,
            p_guide,
        };
        Some((wi, bs, Some(mix)))
    }
}

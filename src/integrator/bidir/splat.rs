//! t = 1: the light subpath's origin y_0 and every stored light vertex connected to the
//! sensor — the whole of light tracing (without MIS) and BDPT's t = 1 techniques (with it).
//! For the camera the contributions splat to the pixels they land in; for a meter they all go
//! to its one reading (bin 0).

use super::connect::{origin_to_sensor, vertex_to_sensor};
use super::origin_view::may_be_seen;
use super::{BidirContext, Workspace};
use crate::sampling::Sampler;
use crate::spectral::SampledWavelengths;

/// Connects `ws.light` to the sensor of `ctx`, recording the contributions in `ws.record`
/// (strategy (s, 1) for a vertex of depth s − 1). One 2D sample per connection attempt, so
/// the sampler's stream does not depend on which connections succeed; as many as the light
/// subpath has vertices, so they come from the sampler's independent stream
/// ([`Sampler::detached`]), never from the camera's dimensions.
pub fn splat_light_subpath(
    ctx: &BidirContext,
    lambda: &SampledWavelengths,
    sampler: &mut Sampler,
    ws: &mut Workspace,
    use_mis: bool,
) {
    sampler.detached(|s| splat_detached(ctx, lambda, s, ws, use_mis));
}

/// [`splat_light_subpath`] on a sampler without a low-discrepancy stream.
fn splat_detached(
    ctx: &BidirContext,
    lambda: &SampledWavelengths,
    sampler: &mut Sampler,
    ws: &mut Workspace,
    use_mis: bool,
) {
    if let Some(o) = ws.light.origin {
        let u = sampler.get_2d();
        // A lamp outside the camera's view: its points project nowhere (`origin_view.rs`).
        let seen = may_be_seen(ctx.origins_in_view, o.light);
        if let Some(sc) = seen
            .then(|| origin_to_sensor(ctx, &o, lambda, u, use_mis))
            .flatten()
        {
            ws.record.add_splat(sc.bin, 1, sc.c);
        }
    }
    for y in &ws.light.vertices {
        let u = sampler.get_2d();
        if let Some(sc) = vertex_to_sensor(ctx, y, u, use_mis) {
            ws.record.add_splat(sc.bin, y.depth + 1, sc.c);
        }
    }
}

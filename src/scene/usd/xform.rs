//! UsdGeomXformable: composing a prim's `xformOpOrder` into a local-to-parent matrix.
//!
//! openusd's `Xformable::local_to_parent_transform` treats unknown ops and mistyped values as
//! identity; a renderer that reports measurements must not silently misplace geometry, so the
//! stack is composed here with every op validated. Matrices are glam column-vector
//! (`p' = M p`): the first op listed in `xformOpOrder` is the outermost factor.

use glam::{DMat4, DQuat, DVec3};
use openusd::{sdf, usd};

use super::values::{self, Ctx};
use crate::error::Result;

const INVERT_PREFIX: &str = "!invert!";
const RESET_XFORM_STACK: &str = "!resetXformStack!";
const OP_NAMESPACE: &str = "xformOp:";

/// A prim's own transform.
#[derive(Clone, Copy, Debug)]
pub(super) struct LocalXform {
    /// Local-to-parent (stage units).
    pub matrix: DMat4,
    /// `!resetXformStack!`: the parent's transform is not inherited.
    pub resets: bool,
}

impl LocalXform {
    /// The identity, inheriting the parent.
    pub const IDENTITY: LocalXform = LocalXform {
        matrix: DMat4::IDENTITY,
        resets: false,
    };

    /// Composes this local transform under `parent_to_world`.
    pub fn under(self, parent_to_world: DMat4) -> DMat4 {
        if self.resets {
            self.matrix
        } else {
            parent_to_world * self.matrix
        }
    }
}

/// Reads and composes the prim's `xformOpOrder`.
pub(super) fn local_xform(ctx: &Ctx, prim: &usd::Prim) -> Result<LocalXform> {
    let Some(order) = op_order(ctx, prim)? else {
        return Ok(LocalXform::IDENTITY);
    };
    let mut xform = LocalXform::IDENTITY;
    for (i, op) in order.iter().enumerate() {
        if op == RESET_XFORM_STACK {
            if i != 0 {
                return Err(ctx.err(
                    prim,
                    "'!resetXformStack!' must be the first entry of xformOpOrder",
                ));
            }
            xform.resets = true;
            continue;
        }
        xform.matrix *= op_matrix(ctx, prim, op)?;
    }
    Ok(xform)
}

/// The authored `xformOpOrder` tokens.
fn op_order(ctx: &Ctx, prim: &usd::Prim) -> Result<Option<Vec<String>>> {
    let order = match ctx.raw(prim, "xformOpOrder")? {
        None => return Ok(None),
        Some(sdf::Value::TokenVec(v)) => v.iter().map(|t| t.as_str().to_string()).collect(),
        Some(sdf::Value::StringVec(v)) => v,
        Some(v) => {
            let reason = format!("'xformOpOrder' is {}, expected token[]", values::kind(&v));
            return Err(ctx.err(prim, reason));
        }
    };
    Ok(Some(order))
}

/// The matrix of one entry of `xformOpOrder`, `!invert!` applied.
fn op_matrix(ctx: &Ctx, prim: &usd::Prim, entry: &str) -> Result<DMat4> {
    let (inverted, attr) = match entry.strip_prefix(INVERT_PREFIX) {
        Some(rest) => (true, rest),
        None => (false, entry),
    };
    let Some(op) = attr.strip_prefix(OP_NAMESPACE) else {
        return Err(ctx.err(
            prim,
            format!("xformOpOrder entry '{entry}' is not an xformOp"),
        ));
    };
    let op_type = op.split(':').next().unwrap_or(op);
    let Some(value) = ctx.raw(prim, attr)? else {
        return Err(ctx.err(
            prim,
            format!("xformOpOrder names '{attr}' but it has no value"),
        ));
    };
    let matrix = op_type_matrix(op_type, &value).ok_or_else(|| {
        ctx.err(
            prim,
            format!(
                "'{attr}': unsupported op or value of type {}",
                values::kind(&value)
            ),
        )
    })?;
    if !matrix.is_finite() {
        return Err(ctx.err(prim, format!("'{attr}' is not finite (NaN or Inf)")));
    }
    if !inverted {
        return Ok(matrix);
    }
    if matrix.determinant().abs() < 1e-300 {
        return Err(ctx.err(
            prim,
            format!("'{entry}': the op is singular and cannot be inverted"),
        ));
    }
    Ok(matrix.inverse())
}

/// The matrix of an op of type `op_type` (`translate`, `rotateXYZ`, ...) with `value`;
/// `None` for an unknown op type or a value of the wrong type.
pub(super) fn op_type_matrix(op_type: &str, value: &sdf::Value) -> Option<DMat4> {
    let vec3 = || values::to_vec3(value).map(DVec3::from_array);
    let scalar = || values::to_f64(value);
    Some(match op_type {
        "translate" => DMat4::from_translation(vec3()?),
        "translateX" => DMat4::from_translation(DVec3::X * scalar()?),
        "translateY" => DMat4::from_translation(DVec3::Y * scalar()?),
        "translateZ" => DMat4::from_translation(DVec3::Z * scalar()?),
        "scale" => DMat4::from_scale(vec3()?),
        "scaleX" => DMat4::from_scale(DVec3::new(scalar()?, 1.0, 1.0)),
        "scaleY" => DMat4::from_scale(DVec3::new(1.0, scalar()?, 1.0)),
        "scaleZ" => DMat4::from_scale(DVec3::new(1.0, 1.0, scalar()?)),
        "rotateX" => DMat4::from_rotation_x(scalar()?.to_radians()),
        "rotateY" => DMat4::from_rotation_y(scalar()?.to_radians()),
        "rotateZ" => DMat4::from_rotation_z(scalar()?.to_radians()),
        "orient" => DMat4::from_quat(orient(value)?),
        "transform" => DMat4::from_cols_array(&values::to_matrix4(value)?),
        _ => euler(op_type, vec3()?)?,
    })
}

/// A normalised `orient` quaternion (`None` for a zero quaternion).
fn orient(value: &sdf::Value) -> Option<DQuat> {
    let [w, x, y, z] = values::to_quat(value)?;
    let q = DQuat::from_xyzw(x, y, z, w);
    (q.length() > 1e-12).then(|| q.normalize())
}

/// A three-axis rotation `rotateABC` (degrees): A is applied first, then B, then C.
fn euler(op_type: &str, degrees: DVec3) -> Option<DMat4> {
    let axes = op_type.strip_prefix("rotate")?;
    if axes.len() != 3 {
        return None;
    }
    let mut m = DMat4::IDENTITY;
    let mut seen = [false; 3];
    for axis in axes.chars() {
        let (i, r) = match axis {
            'X' => (0, DMat4::from_rotation_x(degrees.x.to_radians())),
            'Y' => (1, DMat4::from_rotation_y(degrees.y.to_radians())),
            'Z' => (2, DMat4::from_rotation_z(degrees.z.to_radians())),
            _ => return None,
        };
        if std::mem::replace(&mut seen[i], true) {
            return None;
        }
        m = r * m;
    }
    Some(m)
}

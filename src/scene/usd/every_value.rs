//! Reads every attribute of every prim of a stage at several times: the check, for the tests,
//! that everything a stage authors decodes (openusd decodes crate values lazily, so loading
//! a stage reads only the attributes the renderer needs).

use openusd::{sdf, usd};
use std::path::Path;

use super::guard;
use crate::error::{Error, Result};

/// Reads every attribute's default and its value at each of `times` (linear interpolation),
/// and every relationship's targets; returns how many values were read.
pub fn read_every_value(path: &Path, times: &[f64]) -> Result<usize> {
    guard::catch_panics(path, || {
        let stage = super::open(path)?.stage;
        let mut prims = Vec::new();
        stage
            .traverse(usd::PrimPredicate::ALL, |p| prims.push(p.clone()))
            .map_err(|e| Error::usd(path, format!("traversing the stage: {e:#}")))?;
        let mut count = 0;
        for prim_path in prims {
            let prim = stage.prim(prim_path.clone());
            let fail = |what: &str, e: &dyn std::fmt::Display| {
                Error::prim(path, prim_path.as_str(), format!("{what}: {e:#}"))
            };
            for relationship in prim
                .relationships()
                .map_err(|e| fail("relationships", &e))?
            {
                relationship
                    .targets()
                    .map_err(|e| fail("a relationship", &e))?;
                count += 1;
            }
            for attribute in prim.attributes().map_err(|e| fail("attributes", &e))? {
                let name = attribute.path().as_str().to_string();
                attribute
                    .get_at::<sdf::Value>(None)
                    .map_err(|e| fail(&name, &e))?;
                for &t in times {
                    attribute
                        .get_at::<sdf::Value>(usd::TimeCode::new(t))
                        .map_err(|e| fail(&name, &e))?;
                }
                count += 1 + times.len();
            }
        }
        Ok(count)
    })
}

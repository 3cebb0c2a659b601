//! The scene's emission-weighted layers (`light::emission_layers`): the illuminant layers of
//! `--illuminants`, the light groups of `--light-groups`, and the replacement of every
//! light's spectrum by one illuminant (`--illuminant`, the separate render an illuminant
//! layer equals). The light sampler is left as the scene built it, from the original
//! lights' luminous powers: every layer, and a replaced scene, selects lights the same way.

use super::Scene;
use crate::desc::SceneDescription;
use crate::error::{Error, Result};
use crate::light::emission_layers::{
    illuminant_name, replaced, unit_illuminant, EmissionLayer, LayerSource,
};
use crate::light::Light;
use std::collections::HashMap;

/// Per light, its group: the `spectral:lightGroup` token of its prim, else the prim's name
/// (its full path, `/` as `_`, when two lights' prims share a name).
pub fn group_names(desc: &SceneDescription, lights: &[Light]) -> Vec<String> {
    let tokens: HashMap<&str, &str> = desc
        .lights
        .iter()
        .filter_map(|l| Some((l.prim_path.as_str(), l.emission.light_group.as_deref()?)))
        .chain(desc.meshes.iter().filter_map(|m| {
            let g = m.light.as_ref()?.light_group.as_deref()?;
            Some((m.prim_path.as_str(), g))
        }))
        .collect();
    let leaf = |p: &str| p.rsplit('/').next().unwrap_or(p).to_string();
    let mut owners: HashMap<String, &str> = HashMap::new();
    let mut clash = false;
    for l in lights {
        let p = l.prim_path();
        if tokens.contains_key(p) {
            continue;
        }
        clash |= *owners.entry(leaf(p)).or_insert(p) != p;
    }
    lights
        .iter()
        .map(|l| {
            let p = l.prim_path();
            match tokens.get(p) {
                Some(g) => g.to_string(),
                None if clash => p.trim_start_matches('/').replace('/', "_"),
                None => leaf(p),
            }
        })
        .collect()
}

impl Scene {
    /// Replaces every light's spectrum by the illuminant `name` (or its short form) at the
    /// same base luminance, keeping the light sampler.
    pub fn replace_emission(&mut self, name: &str) -> Result<()> {
        self.lights = self.replaced_lights(name)?.1;
        Ok(())
    }

    /// Adds one layer per illuminant, named by its full name (`CIE-A`).
    pub fn add_illuminant_layers(&mut self, names: &[String]) -> Result<()> {
        for name in names {
            let (full, lights) = self.replaced_lights(name)?;
            self.push_layer(full.to_string(), LayerSource::Replaced(lights))?;
        }
        Ok(())
    }

    /// Adds one layer per light group (`light_groups`), in the order the groups' first
    /// lights come.
    pub fn add_light_group_layers(&mut self) -> Result<()> {
        let mut names: Vec<&String> = Vec::new();
        for g in &self.light_groups {
            if !names.contains(&g) {
                names.push(g);
            }
        }
        let groups: Vec<(String, Vec<bool>)> = names
            .into_iter()
            .map(|g| {
                (
                    g.clone(),
                    self.light_groups.iter().map(|x| x == g).collect(),
                )
            })
            .collect();
        for (name, mask) in groups {
            self.push_layer(name, LayerSource::Group(mask))?;
        }
        Ok(())
    }

    fn push_layer(&mut self, name: String, source: LayerSource) -> Result<()> {
        if self.emission_layers.layers.iter().any(|l| l.name == name) {
            return Err(Error::option(format!(
                "two layers would be named '{name}' (an illuminant given twice, or a light \
                 group named like an illuminant)"
            )));
        }
        self.emission_layers
            .layers
            .push(EmissionLayer { name, source });
        Ok(())
    }

    fn replaced_lights(&self, name: &str) -> Result<(&'static str, Vec<Light>)> {
        let full = illuminant_name(name).map_err(Error::option)?;
        let unit = unit_illuminant(full).map_err(Error::option)?;
        let lights = self
            .lights
            .iter()
            .map(|l| replaced(l, &unit).map_err(|r| Error::prim(&self.source, l.prim_path(), r)))
            .collect::<Result<Vec<_>>>()?;
        Ok((full, lights))
    }
}

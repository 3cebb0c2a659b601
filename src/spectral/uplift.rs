//! PLACEHOLDER — owned by the uplift helper; replaced wholesale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sigmoid {
    pub c: [f32; 3],
}
impl Sigmoid {
    pub fn eval(&self, _lambda: f32) -> f32 {
        unimplemented!()
    }
}
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbIlluminantSpectrum {
    pub scale: f32,
    pub sigmoid: Sigmoid,
}
impl RgbIlluminantSpectrum {
    pub fn eval(&self, _lambda: f32) -> f32 {
        unimplemented!()
    }
    pub fn scaled(&self, s: f32) -> Self {
        RgbIlluminantSpectrum {
            scale: self.scale * s,
            ..*self
        }
    }
}

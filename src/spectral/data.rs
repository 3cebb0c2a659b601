//! PLACEHOLDER — owned by the spectra-data helper; replaced wholesale.
use super::dense::DenseSpectrum;

pub fn cie_xyz() -> &'static [DenseSpectrum; 3] {
    unimplemented!()
}
pub fn cie_v() -> &'static DenseSpectrum {
    unimplemented!()
}
pub fn illuminant(_name: &str) -> Option<&'static DenseSpectrum> {
    unimplemented!()
}
pub fn named(_name: &str) -> Option<&'static DenseSpectrum> {
    unimplemented!()
}

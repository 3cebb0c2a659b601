//! Running the `spectral-render` binary, and the colour-science checks of `tools/`.

use std::path::Path;
use std::process::{Command, Output};

/// Runs `spectral-render` with `args` in `cwd`.
pub fn spectral_render(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_spectral-render"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run spectral-render")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Makes the Python venv with colour-science (`tools/venv.sh`).
pub fn colour_science_venv() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let status = Command::new("bash")
        .arg(root.join("tools/venv.sh"))
        .status()
        .expect("run tools/venv.sh");
    assert!(status.success(), "tools/venv.sh failed");
}

/// Runs `tools/<script>` on `json` with the venv's Python: whether it passed, and its stdout
/// followed by its stderr.
pub fn colour_science_check(script: &str, json: &Path) -> (bool, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let check = Command::new(root.join(".venv/bin/python"))
        .arg(root.join("tools").join(script))
        .arg(json)
        .output()
        .unwrap_or_else(|e| panic!("run {script}: {e:?}"));
    let report = format!(
        "{}{}",
        String::from_utf8_lossy(&check.stdout),
        String::from_utf8_lossy(&check.stderr)
    );
    (check.status.success(), report)
}

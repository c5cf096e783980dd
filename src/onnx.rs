//! User-supplied ONNX models (inpainting, monocular depth, depth refinement, metrics) run through
//! onnxruntime, loaded at run time: no model and no onnxruntime are needed unless a model is given.
//!
//! The shared library is found at `ORT_DYLIB_PATH`, else at the place `scripts/setup.sh` installs it
//! (`$XDG_CACHE_HOME` or `~/.cache`, then `cogeo/onnxruntime/libonnxruntime.so.1.31.1`).
//! onnxruntime runs on the CPU here: the models are the user's and run once per view, while every
//! per-iteration pass stays a Vulkan compute shader.

use anyhow::{anyhow, bail, Context, Result};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

/// The onnxruntime version cogeo is built and tested against.
pub const ORT_LIBRARY: &str = "libonnxruntime.so.1.31.1";

/// Where `scripts/setup.sh` puts the library.
pub fn default_library_path() -> Option<PathBuf> {
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(cache.join("cogeo/onnxruntime").join(ORT_LIBRARY))
}

static ENVIRONMENT: OnceLock<Mutex<Option<std::result::Result<ort::environment::Environment, String>>>> =
    OnceLock::new();

/// Loads onnxruntime once per process.
fn environment() -> Result<ort::environment::Environment> {
    let cell = ENVIRONMENT.get_or_init(|| Mutex::new(None));
    let mut guard = cell.lock().map_err(|_| anyhow!("onnxruntime initialization panicked"))?;
    if guard.is_none() {
        let path = std::env::var_os("ORT_DYLIB_PATH").map(PathBuf::from).or_else(default_library_path);
        let result = match path {
            Some(p) if p.exists() => ort::init_from(&p)
                .map_err(|e| format!("{}: cannot load onnxruntime: {e}", p.display()))
                .and_then(|b| b.with_name("cogeo").build().map_err(|e| format!("{}: onnxruntime: {e}", p.display()))),
            Some(p) => Err(format!(
                "onnxruntime not found at {} (set ORT_DYLIB_PATH to {ORT_LIBRARY} from the PyPI onnxruntime wheel, \
                 or run scripts/setup.sh, which installs it)",
                p.display()
            )),
            None => Err("onnxruntime not found: set ORT_DYLIB_PATH".into()),
        };
        *guard = Some(result);
    }
    guard.as_ref().unwrap().clone().map_err(|e| anyhow!(e))
}

/// A float tensor: shape and row-major values.
#[derive(Clone, Debug, PartialEq)]
pub struct Tensor {
    pub shape: Vec<i64>,
    pub data: Vec<f32>,
}

impl Tensor {
    pub fn new(shape: Vec<i64>, data: Vec<f32>) -> Tensor {
        debug_assert_eq!(shape.iter().product::<i64>() as usize, data.len());
        Tensor { shape, data }
    }
}

/// One loaded ONNX model.
pub struct Model {
    /// Behind a lock: a run needs the session mutably, and a model is shared by the threads
    /// that complete views in parallel.
    session: std::sync::Mutex<ort::session::Session>,
    path: PathBuf,
    inputs: Vec<String>,
    outputs: Vec<String>,
}

impl Model {
    /// Loads `path`. Errors name the file.
    pub fn load(path: &Path) -> Result<Model> {
        if !path.is_file() {
            bail!("{}: ONNX model not found", path.display());
        }
        let env = environment()?;
        let session = ort::session::Session::builder(&env)
            .and_then(|mut b| b.commit_from_file(path))
            .map_err(|e| anyhow!("{}: cannot load the ONNX model: {e}", path.display()))?;
        let inputs = session.inputs().iter().map(|o| o.name().to_string()).collect();
        let outputs = session.outputs().iter().map(|o| o.name().to_string()).collect();
        Ok(Model { session: std::sync::Mutex::new(session), path: path.to_path_buf(), inputs, outputs })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn input_names(&self) -> &[String] {
        &self.inputs
    }

    pub fn output_names(&self) -> &[String] {
        &self.outputs
    }

    /// Fails unless the model has exactly these inputs (any order) and at least `outputs` outputs.
    pub fn expect(&self, contract: &str, inputs: &[&str], outputs: usize) -> Result<()> {
        let mut have: Vec<&str> = self.inputs.iter().map(|s| s.as_str()).collect();
        let mut want = inputs.to_vec();
        have.sort();
        want.sort();
        if have != want {
            bail!(
                "{}: the {contract} contract needs inputs {:?}, the model has {:?}",
                self.path.display(),
                inputs,
                self.inputs
            );
        }
        if self.outputs.len() < outputs {
            bail!(
                "{}: the {contract} contract needs {outputs} output(s), the model has {:?}",
                self.path.display(),
                self.outputs
            );
        }
        Ok(())
    }

    /// Runs the model on named float inputs; returns every output in the model's order.
    pub fn run(&self, inputs: &[(&str, &Tensor)]) -> Result<Vec<Tensor>> {
        let mut values = Vec::with_capacity(inputs.len());
        for (name, t) in inputs {
            let v = ort::value::Tensor::from_array((t.shape.clone(), t.data.clone()))
                .map_err(|e| anyhow!("{}: input {name}: {e}", self.path.display()))?;
            values.push((std::borrow::Cow::from(name.to_string()), ort::session::SessionInputValue::from(v)));
        }
        let path = self.path.display().to_string();
        let mut session = self.session.lock().map_err(|_| anyhow!("{path}: a model run panicked"))?;
        let outputs = session.run(values).map_err(|e| anyhow!("{path}: inference failed: {e}"))?;
        let mut result = Vec::new();
        for name in &self.outputs {
            let (shape, data) = outputs[name.as_str()]
                .try_extract_tensor::<f32>()
                .with_context(|| format!("{path}: output {name} is not a float tensor"))?;
            result.push(Tensor::new(shape.iter().copied().collect(), data.to_vec()));
        }
        Ok(result)
    }
}

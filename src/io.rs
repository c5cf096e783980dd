//! Output helpers: every file is written to a temporary name beside its target and renamed into place,
//! so a killed run never leaves a half-written file.

use anyhow::{Context, Result};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Removes the temporary files that killed writers of `path` left beside it: `.{name}.{pid}.tmp`
/// whose process is gone (a live pid, even a reused one, keeps its file).
fn sweep_stale_temps(path: &Path) {
    let (Some(dir), Some(name)) = (path.parent(), path.file_name()) else { return };
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    let prefix = format!(".{}.", name.to_string_lossy());
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = file.strip_prefix(&prefix).and_then(|r| r.strip_suffix(".tmp")) else { continue };
        if pid.parse::<u32>().is_ok_and(|p| p != std::process::id() && !Path::new(&format!("/proc/{p}")).exists()) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Finished temporary files waiting for the open output batch's commit: (temporary, target).
static BATCH: std::sync::Mutex<Option<Vec<(PathBuf, PathBuf)>>> = std::sync::Mutex::new(None);

/// The outputs of one command, made to appear together: while a batch is open, `write_atomic`
/// leaves each finished (synced) file under its temporary name, and `commit` renames them all into
/// place. Whatever fails before the commit (a full disk on the last file, a device error) leaves
/// every previous output as it was, and the batch, dropped uncommitted, deletes its temporaries.
/// One batch per process (a command), opened after the command last reads its own outputs.
pub struct OutputBatch(());

impl OutputBatch {
    pub fn begin() -> OutputBatch {
        let mut batch = BATCH.lock().unwrap();
        debug_assert!(batch.is_none(), "an output batch is already open");
        *batch = Some(Vec::new());
        OutputBatch(())
    }

    /// Renames every file of the batch into place, in the order they were written.
    pub fn commit(self) -> Result<()> {
        for (tmp, path) in BATCH.lock().unwrap().take().unwrap_or_default() {
            std::fs::rename(&tmp, &path).with_context(|| format!("{}: cannot move into place", path.display()))?;
        }
        Ok(())
    }
}

impl Drop for OutputBatch {
    /// After a commit the list is gone; before one, its temporaries are deleted.
    fn drop(&mut self) {
        if let Some(list) = BATCH.lock().unwrap().take() {
            for (tmp, _) in list {
                let _ = std::fs::remove_file(tmp);
            }
        }
    }
}

/// Writes through `body` into a temporary file, syncs it and renames it onto `path` (at once, or
/// at the commit of an open `OutputBatch`). On any error (a full disk included) the temporary
/// file is removed and `path` keeps its old content.
pub fn write_atomic(path: &Path, body: impl FnOnce(&mut BufWriter<std::fs::File>) -> Result<()>) -> Result<()> {
    sweep_stale_temps(path);
    let tmp = temp_path(path);
    let result = (|| -> Result<()> {
        let file = std::fs::File::create(&tmp).with_context(|| format!("{}: cannot create", tmp.display()))?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        body(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        if let Some(batch) = BATCH.lock().unwrap().as_mut() {
            if !batch.iter().any(|(t, _)| *t == tmp) {
                batch.push((tmp.clone(), path.to_path_buf()));
            }
            return Ok(());
        }
        std::fs::rename(&tmp, path).with_context(|| format!("{}: cannot move into place", path.display()))?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("writing {}", path.display()))
}

/// The largest image width or height cogeo accepts (pixel counts stay below 2^30, so pixel indices
/// fit u32 arithmetic everywhere).
pub const MAX_IMAGE_SIDE: u32 = 32768;

/// Decodes an image file's bytes (PNG or JPEG, found from the content), refusing sizes beyond
/// `MAX_IMAGE_SIDE` per side, before any pixel memory is taken. The decoder may allocate at most
/// 2048 bytes per byte of file (+16 MiB): deflate cannot compress more than about 1032:1, so a
/// real image always fits, while a 200-byte file whose header claims 30000 x 30000 pixels is
/// refused instead of taking a gigabyte. `what` names the file in errors.
pub fn decode_image(data: &[u8], what: &str) -> Result<image::DynamicImage> {
    let side = MAX_IMAGE_SIDE;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(side);
    limits.max_image_height = Some(side);
    limits.max_alloc = Some((16 << 20) + 2048 * data.len() as u64);
    let mut reader = image::ImageReader::new(std::io::Cursor::new(data))
        .with_guessed_format()
        .with_context(|| format!("{what}: cannot read image"))?;
    reader.limits(limits);
    reader.decode().map_err(|e| anyhow::anyhow!("{what}: cannot decode image ({e})"))
}

/// Reads and decodes an image file (`decode_image`).
pub fn read_image(path: &Path) -> Result<image::DynamicImage> {
    let data = std::fs::read(path).with_context(|| format!("{}: cannot read image", path.display()))?;
    decode_image(&data, &path.display().to_string())
}

/// 8-bit value of a [0, 1] float, rounded; values outside are clamped.
pub fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Writes an RGB PNG from planar float channels in [0, 1] (values are stored as given: the renderer's
/// colors are already in the display space the scene was trained in).
pub fn write_png_rgb(path: &Path, width: u32, height: u32, planar_rgb: &[f32]) -> Result<()> {
    let hw = (width * height) as usize;
    let mut pixels = vec![0u8; hw * 3];
    for i in 0..hw {
        for c in 0..3 {
            pixels[i * 3 + c] = to_u8(planar_rgb[c * hw + i]);
        }
    }
    write_png(path, width, height, image::ColorType::Rgb8, &pixels)
}

/// Writes a single-channel 8-bit PNG from floats in [0, 1].
pub fn write_png_gray(path: &Path, width: u32, height: u32, values: &[f32]) -> Result<()> {
    let pixels: Vec<u8> = values.iter().map(|&v| to_u8(v)).collect();
    write_png(path, width, height, image::ColorType::L8, &pixels)
}

pub fn write_png(path: &Path, width: u32, height: u32, color: image::ColorType, pixels: &[u8]) -> Result<()> {
    write_atomic(path, |w| {
        image::write_buffer_with_format(w, pixels, width, height, color, image::ImageFormat::Png).map_err(Into::into)
    })
}

/// Writes float channels (each width * height, row-major) as a 32-bit float EXR.
pub fn write_exr(path: &Path, width: u32, height: u32, channels: &[(&str, &[f32])]) -> Result<()> {
    use exr::prelude::*;
    let size = Vec2(width as usize, height as usize);
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> =
        channels.iter().map(|(name, data)| AnyChannel::new(*name, FlatSamples::F32(data.to_vec()))).collect();
    let layer = Layer::new(size, LayerAttributes::default(), Encoding::SMALL_LOSSLESS, AnyChannels::sort(list));
    let image = Image::from_layer(layer);
    write_atomic(path, |w| {
        // exr needs Seek; buffer in memory first
        let mut cursor = std::io::Cursor::new(Vec::new());
        image.write().to_buffered(&mut cursor).map_err(|e| anyhow::anyhow!("EXR encoding failed: {e}"))?;
        w.write_all(cursor.get_ref())?;
        Ok(())
    })
}

/// Reads a single float channel from an EXR (the first channel, or the one named `name`).
pub fn read_exr_channel(path: &Path, name: Option<&str>) -> Result<(u32, u32, Vec<f32>)> {
    use exr::prelude::*;
    let image = read_all_flat_layers_from_file(path).with_context(|| format!("{}: cannot read EXR", path.display()))?;
    let layer = image.layer_data.first().ok_or_else(|| anyhow::anyhow!("{}: EXR without layers", path.display()))?;
    let channel = match name {
        Some(n) => layer.channel_data.list.iter().find(|c| c.name.to_string() == n),
        None => layer.channel_data.list.first(),
    }
    .ok_or_else(|| anyhow::anyhow!("{}: EXR channel not found", path.display()))?;
    let values = channel.sample_data.values_as_f32().collect();
    Ok((layer.size.0 as u32, layer.size.1 as u32, values))
}

/// Peak resident memory of this process in MiB (VmHWM of /proc/self/status; Linux only). GPU
/// memory on lavapipe is host memory, so on the CPU this covers it too.
pub fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

//! 8-bit RGB images: conversion from linear colour, PNG output (the `png` crate), and the
//! image-difference measure used to check golden images.

use std::io::Write;
use std::path::Path;

use atomic_write_file::AtomicWriteFile;

use crate::SsfrError;

/// An 8-bit sRGB image, row major, row 0 at the top.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RgbImage {
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
    /// `3 · width · height` bytes (R, G, B).
    pub data: Vec<u8>,
}

/// The sRGB transfer function of a linear value in [0, 1].
#[inline]
fn srgb(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let y = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (y * 255.0 + 0.5) as u8
}

impl RgbImage {
    /// From linear colours (clamped to [0, 1], sRGB-encoded).
    pub fn from_linear(width: usize, height: usize, colour: &[[f32; 3]]) -> Self {
        let mut data = Vec::with_capacity(3 * colour.len());
        for c in colour {
            data.extend(c.iter().map(|&x| srgb(x)));
        }
        Self {
            width,
            height,
            data,
        }
    }

    /// Images side by side (heights must agree), separated by `gap` white columns.
    pub fn side_by_side(images: &[&RgbImage], gap: usize) -> Result<RgbImage, SsfrError> {
        let Some(first) = images.first() else {
            return Err(SsfrError::ImageSize {
                width: 0,
                height: 0,
                reason: "no image to put side by side",
            });
        };
        let h = first.height;
        if images.iter().any(|im| im.height != h) {
            return Err(SsfrError::invalid(
                "side_by_side",
                "images of different heights",
            ));
        }
        let w: usize = images.iter().map(|im| im.width).sum::<usize>() + gap * (images.len() - 1);
        let mut data = vec![255u8; 3 * w * h];
        let mut x0 = 0;
        for im in images {
            for j in 0..h {
                let src = &im.data[3 * j * im.width..3 * (j + 1) * im.width];
                data[3 * (j * w + x0)..3 * (j * w + x0 + im.width)].copy_from_slice(src);
            }
            x0 += im.width + gap;
        }
        Ok(RgbImage {
            width: w,
            height: h,
            data,
        })
    }

    /// Writes a PNG, atomically: the file appears complete or not at all (written to an
    /// unnamed temporary file in the same directory, then linked into place), so that a
    /// reader never sees half an image and a failed write leaves the old file.
    pub fn write_png(&self, path: &Path) -> Result<(), SsfrError> {
        let io = |e: String| SsfrError::Io {
            path: path.to_path_buf(),
            reason: e,
        };
        if self.data.len() != 3 * self.width * self.height {
            return Err(io(format!(
                "{} bytes for a {}x{} RGB image ({} expected)",
                self.data.len(),
                self.width,
                self.height,
                3 * self.width * self.height
            )));
        }
        let (width, height) = (u32::try_from(self.width), u32::try_from(self.height));
        let (Ok(width), Ok(height)) = (width, height) else {
            return Err(io("image too large for PNG".into()));
        };
        // Encoded in memory first, so that every write error reaches the caller (a buffered
        // writer dropped by the encoder would swallow the last one).
        let mut encoded = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut encoded, width, height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header().map_err(|e| io(e.to_string()))?;
            writer
                .write_image_data(&self.data)
                .map_err(|e| io(e.to_string()))?;
            writer.finish().map_err(|e| io(e.to_string()))?;
        }
        let mut file = AtomicWriteFile::open(path).map_err(|e| io(e.to_string()))?;
        file.write_all(&encoded).map_err(|e| io(e.to_string()))?;
        file.commit().map_err(|e| io(e.to_string()))
    }

    /// Reads an 8-bit RGB or RGBA PNG (alpha dropped).
    pub fn read_png(path: &Path) -> Result<RgbImage, SsfrError> {
        let io = |e: String| SsfrError::Io {
            path: path.to_path_buf(),
            reason: e,
        };
        let file = std::fs::File::open(path).map_err(|e| io(e.to_string()))?;
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .map_err(|e| io(e.to_string()))?;
        // Bounded by the decoder's default limit on decoded bytes (png::Limits).
        let size = reader.output_buffer_size();
        let mut buf = Vec::new();
        buf.try_reserve_exact(size)
            .map_err(|e| io(format!("{size} bytes for the decoded image: {e}")))?;
        buf.resize(size, 0);
        let info = reader.next_frame(&mut buf).map_err(|e| io(e.to_string()))?;
        if info.bit_depth != png::BitDepth::Eight {
            return Err(io("not an 8-bit PNG".into()));
        }
        let ch = match info.color_type {
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            other => return Err(io(format!("colour type {other:?}: RGB or RGBA expected"))),
        };
        let (w, h) = (info.width as usize, info.height as usize);
        let mut data = Vec::with_capacity(3 * w * h);
        for j in 0..h {
            let row = &buf[j * info.line_size..j * info.line_size + ch * w];
            for px in row.chunks(ch) {
                data.extend_from_slice(&px[..3]);
            }
        }
        Ok(RgbImage {
            width: w,
            height: h,
            data,
        })
    }
}

/// Difference of two images of the same size: `(mean |Δ|, fraction of pixels whose largest
/// channel difference exceeds `threshold`)`, with channel values in [0, 1]. The measure of
/// the golden-image checks.
pub fn image_difference(
    a: &RgbImage,
    b: &RgbImage,
    threshold: f32,
) -> Result<(f64, f64), SsfrError> {
    if a.width != b.width || a.height != b.height {
        return Err(SsfrError::invalid(
            "image_difference",
            format!(
                "sizes differ: {}x{} vs {}x{}",
                a.width, a.height, b.width, b.height
            ),
        ));
    }
    let n = (a.width * a.height).max(1);
    let mut sum = 0.0f64;
    let mut over = 0usize;
    for (pa, pb) in a.data.chunks(3).zip(b.data.chunks(3)) {
        let mut worst = 0.0f32;
        for k in 0..3 {
            let d = (pa[k] as f32 - pb[k] as f32).abs() / 255.0;
            sum += d as f64;
            worst = worst.max(d);
        }
        if worst > threshold {
            over += 1;
        }
    }
    Ok((sum / (3 * n) as f64, over as f64 / n as f64))
}

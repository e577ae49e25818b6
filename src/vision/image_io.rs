//! Decoding connector images (PNG, JPEG, BMP, TIFF, ... 8 or 16 bit, grey or
//! colour) into a [`Gray`] image at full precision.
//!
//! The header is read first and checked before any pixel buffer exists, so
//! a file whose header claims absurd dimensions is refused without
//! allocating (the decoder also runs under `image::Limits`). Colour is
//! converted to luma with the Rec. 709 weights (spec/vision.md) and kept in
//! 16 bits, so no precision is lost to rounding; 16-bit grey stays 16-bit.

use super::error::VisionError;
use super::gray::{Gray, ImageInfo};
use image::{DynamicImage, ImageDecoder, ImageReader, Limits};
use std::io::Cursor;
use std::path::Path;

/// Largest image accepted, in megapixels (a 5 MP camera is the norm).
pub const MAX_MEGAPIXELS: u32 = 64;
/// Smallest image accepted (width and height).
pub const MIN_SIDE: u32 = 16;

/// Reads and decodes an image file.
pub fn load_path(path: &Path) -> Result<(Gray, ImageInfo), VisionError> {
    let bytes = crate::input::read_bounded(path, crate::input::IMAGE_MAX_BYTES)
        .map_err(|e| VisionError::Io(e.to_string()))?;
    decode_bytes(&bytes)
}

/// Decodes an image held in memory (a file's bytes, or a rig log's
/// `CompressedImage.data`).
pub fn decode_bytes(bytes: &[u8]) -> Result<(Gray, ImageInfo), VisionError> {
    if bytes.is_empty() {
        return Err(VisionError::Empty);
    }
    let reader = ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| VisionError::Io(e.to_string()))?;
    let Some(format) = reader.format() else {
        let head: Vec<String> = bytes.iter().take(8).map(|b| format!("{b:02x}")).collect();
        return Err(VisionError::NotImage(head.join(" ")));
    };
    let fmt_name = format
        .extensions_str()
        .first()
        .copied()
        .unwrap_or("image")
        .to_string();
    let fmt_name = if fmt_name == "jpg" {
        "jpeg".to_string()
    } else {
        fmt_name
    };
    let decode_err = |e: image::ImageError| VisionError::Decode {
        format: fmt_name.clone(),
        msg: e.to_string(),
    };

    // A header that claims an empty image: say so, in its own numbers
    // (some decoders call a zero width "too large").
    if let Some((width, height)) = header_dims(format, bytes)
        && (width == 0 || height == 0)
    {
        return Err(VisionError::TooSmall {
            width,
            height,
            min: MIN_SIDE,
        });
    }
    let mut limits = Limits::default();
    // Output buffer (≤ 64 Mpx × 8 bytes) plus decoder working memory.
    limits.max_alloc = Some(768 * 1024 * 1024);
    let mut reader = reader;
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(|e| match e {
        image::ImageError::Limits(l) => VisionError::LimitExceeded(l.to_string()),
        e => decode_err(e),
    })?;
    let (width, height) = decoder.dimensions();
    if width as u64 * height as u64 > MAX_MEGAPIXELS as u64 * 1_000_000 {
        return Err(VisionError::TooLarge {
            width,
            height,
            limit_mpx: MAX_MEGAPIXELS,
        });
    }
    if width < MIN_SIDE || height < MIN_SIDE {
        return Err(VisionError::TooSmall {
            width,
            height,
            min: MIN_SIDE,
        });
    }
    let color = decoder.color_type();
    let info = ImageInfo {
        width,
        height,
        channels: color.channel_count(),
        bit_depth: (color.bits_per_pixel() / color.channel_count() as u16).min(255) as u8,
        format: fmt_name.clone(),
    };
    let img = DynamicImage::from_decoder(decoder).map_err(|e| match e {
        image::ImageError::Limits(l) => VisionError::LimitExceeded(l.to_string()),
        e => decode_err(e),
    })?;
    Ok((to_gray(img), info))
}

/// The width and height a PNG or BMP header claims, read before any decoder
/// runs (None for other formats or a header too short to hold them).
fn header_dims(format: image::ImageFormat, b: &[u8]) -> Option<(u32, u32)> {
    let be = |i: usize| Some(u32::from_be_bytes(b.get(i..i + 4)?.try_into().ok()?));
    let le = |i: usize| Some(i32::from_le_bytes(b.get(i..i + 4)?.try_into().ok()?));
    match format {
        image::ImageFormat::Png => Some((be(16)?, be(20)?)),
        image::ImageFormat::Bmp => Some((le(18)?.unsigned_abs(), le(22)?.unsigned_abs())),
        _ => None,
    }
}

/// Rec. 709 luma of an RGB triple (any scale).
#[inline]
pub fn luma709(r: f32, g: f32, b: f32) -> f32 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// Converts any decoded image to grey at full precision.
pub fn to_gray(img: DynamicImage) -> Gray {
    let (w, h) = (img.width(), img.height());
    let rgb16 = |px: &mut dyn Iterator<Item = [f32; 3]>, scale: f32| -> Gray {
        let data: Vec<u16> = px
            .map(|[r, g, b]| (luma709(r, g, b) * scale).round().clamp(0.0, 65535.0) as u16)
            .collect();
        Gray {
            width: w,
            height: h,
            data: super::gray::GrayData::U16(data),
        }
    };
    match img {
        DynamicImage::ImageLuma8(b) => Gray {
            width: w,
            height: h,
            data: super::gray::GrayData::U8(b.into_raw()),
        },
        DynamicImage::ImageLuma16(b) => Gray {
            width: w,
            height: h,
            data: super::gray::GrayData::U16(b.into_raw()),
        },
        DynamicImage::ImageLumaA8(b) => Gray {
            width: w,
            height: h,
            data: super::gray::GrayData::U8(b.pixels().map(|p| p.0[0]).collect()),
        },
        DynamicImage::ImageLumaA16(b) => Gray {
            width: w,
            height: h,
            data: super::gray::GrayData::U16(b.pixels().map(|p| p.0[0]).collect()),
        },
        DynamicImage::ImageRgb8(b) => rgb16(&mut b.pixels().map(|p| rgb_f32(p.0)), 257.0),
        DynamicImage::ImageRgba8(b) => rgb16(&mut b.pixels().map(|p| rgb_f32(p.0)), 257.0),
        DynamicImage::ImageRgb16(b) => rgb16(&mut b.pixels().map(|p| rgb_f32(p.0)), 1.0),
        DynamicImage::ImageRgba16(b) => rgb16(&mut b.pixels().map(|p| rgb_f32(p.0)), 1.0),
        other => {
            let b = other.to_rgb32f();
            rgb16(&mut b.pixels().map(|p| [p.0[0], p.0[1], p.0[2]]), 65535.0)
        }
    }
}

/// The first three channels of an RGB(A) pixel of any integer depth.
fn rgb_f32<T: Copy + Into<f32>, const C: usize>(p: [T; C]) -> [f32; 3] {
    [p[0].into(), p[1].into(), p[2].into()]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png_bytes(img: DynamicImage) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn decodes_grey_colour_and_16_bit() {
        let g8 = image::GrayImage::from_fn(32, 20, |x, y| image::Luma([(x + y) as u8]));
        let (g, info) = decode_bytes(&png_bytes(DynamicImage::ImageLuma8(g8))).unwrap();
        assert_eq!(
            (info.width, info.height, info.channels, info.bit_depth),
            (32, 20, 1, 8)
        );
        assert_eq!(info.format, "png");
        assert_eq!(g.get(3, 4), 7.0);

        let rgb = image::RgbImage::from_fn(32, 20, |_, _| image::Rgb([200, 100, 50]));
        let (g, info) = decode_bytes(&png_bytes(DynamicImage::ImageRgb8(rgb))).unwrap();
        assert_eq!(info.channels, 3);
        let want = luma709(200.0, 100.0, 50.0) * 257.0;
        assert!(
            (g.get(0, 0) - want).abs() <= 0.5,
            "{} vs {want}",
            g.get(0, 0)
        );

        let g16 = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(32, 20, |x, _| {
            image::Luma([x as u16 * 100])
        });
        let (g, info) = decode_bytes(&png_bytes(DynamicImage::ImageLuma16(g16))).unwrap();
        assert_eq!(info.bit_depth, 16);
        assert_eq!(g.get(31, 0), 3100.0);
    }

    #[test]
    fn bad_inputs_are_clear_errors() {
        assert_eq!(decode_bytes(&[]), Err(VisionError::Empty));
        assert!(matches!(
            decode_bytes(b"hello, world, not an image"),
            Err(VisionError::NotImage(_))
        ));
        let one = png_bytes(DynamicImage::ImageLuma8(image::GrayImage::new(1, 1)));
        assert!(matches!(
            decode_bytes(&one),
            Err(VisionError::TooSmall {
                width: 1,
                height: 1,
                ..
            })
        ));
        let full = png_bytes(DynamicImage::ImageLuma8(image::GrayImage::from_fn(
            64,
            64,
            |x, y| image::Luma([(x * y) as u8]),
        )));
        let cut = &full[..full.len() / 2];
        assert!(
            matches!(decode_bytes(cut), Err(VisionError::Decode { .. })),
            "{:?}",
            decode_bytes(cut)
        );
    }

    #[test]
    fn absurd_header_dimensions_are_refused_before_allocation() {
        // A PNG whose IHDR claims 60000 × 60000 px (3.6 Gpx), followed by nothing.
        let mut png = Vec::new();
        png.extend_from_slice(b"\x89PNG\r\n\x1a\n");
        let mut ihdr = Vec::new();
        ihdr.extend_from_slice(b"IHDR");
        ihdr.extend_from_slice(&60000u32.to_be_bytes());
        ihdr.extend_from_slice(&60000u32.to_be_bytes());
        ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
        png.extend_from_slice(&13u32.to_be_bytes());
        png.extend_from_slice(&ihdr);
        png.extend_from_slice(&crc32(&ihdr).to_be_bytes());
        let idat = b"IDAT\x78\x9c\x03\x00\x00\x00\x00\x01";
        png.extend_from_slice(&((idat.len() - 4) as u32).to_be_bytes());
        png.extend_from_slice(idat);
        png.extend_from_slice(&crc32(idat).to_be_bytes());
        let e = decode_bytes(&png).unwrap_err();
        assert!(matches!(e, VisionError::TooLarge { .. }), "{e}");
        assert!(e.to_string().contains("refusing"));
        assert!(e.to_string().contains("60000 × 60000"), "{e}");
    }

    fn crc32(data: &[u8]) -> u32 {
        let mut crc = 0xffff_ffffu32;
        for &b in data {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xedb8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
}

//! The error of a picture against a reference picture (`hirad solve --image A.exr
//! --reference-image B.exr`): how far the light a viewer sees is from the reference's,
//! smoothing and noise included, pixel by pixel.

use super::frame::Frame;

/// The relative L2 error of `image` against `reference` in percent:
/// `100 sqrt(sum (a - r)^2) / sqrt(sum r^2)` over every pixel and channel. `Err` when the
/// two differ in size or channels, or the reference is black.
pub fn image_error_percent(image: &Frame, reference: &Frame) -> Result<f64, String> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(format!(
            "the reference image is {}x{} pixels, the image {}x{}",
            reference.width, reference.height, image.width, image.height
        ));
    }
    if image.channels != reference.channels {
        return Err(format!(
            "the reference image has channels {}, the image {}",
            reference.channels.join(","),
            image.channels.join(",")
        ));
    }
    let (mut diff, mut norm) = (0.0f64, 0.0f64);
    for (&a, &r) in image.data.iter().zip(&reference.data) {
        let (a, r) = (a as f64, r as f64);
        diff += (a - r) * (a - r);
        norm += r * r;
    }
    if norm.is_nan() || norm <= 0.0 || !diff.is_finite() {
        return Err("the reference image is black: nothing to compare with".into());
    }
    Ok(100.0 * (diff / norm).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(w: u32, h: u32, data: Vec<f32>) -> Frame {
        Frame {
            width: w,
            height: h,
            channels: vec!["Y".into()],
            data,
        }
    }

    #[test]
    fn relative_l2_of_known_differences() {
        let r = frame(2, 1, vec![3.0, 4.0]);
        assert_eq!(image_error_percent(&r, &r).unwrap(), 0.0);
        // |(0.3, -0.4)| / |(3, 4)| = 0.5 / 5.
        let a = frame(2, 1, vec![3.3, 3.6]);
        assert!((image_error_percent(&a, &r).unwrap() - 10.0).abs() < 1e-4);
        assert!(image_error_percent(&frame(1, 2, vec![3.0, 4.0]), &r).is_err());
        assert!(image_error_percent(&r, &frame(2, 1, vec![0.0, 0.0])).is_err());
        let mut rgb = r.clone();
        rgb.channels = vec!["R".into()];
        assert!(image_error_percent(&rgb, &r).is_err());
    }
}

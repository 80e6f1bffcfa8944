//! What can go wrong showing frames, and the pixel format every copy
//! presenter writes (shared by the presenters and the output search).

use std::path::PathBuf;

use thiserror::Error;

use crate::render::headless::Image;

/// Why frames cannot be shown.
#[derive(Debug, Error)]
pub enum PresentError {
    #[error(transparent)]
    Kms(#[from] crate::platform::kms::KmsError),
    #[error("{0}")]
    NoOutput(String),
    #[error(
        "{path}: cannot become DRM master: {source} (another program drives the display: stop the display manager, or switch marionette to a free VT)"
    )]
    Master {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {what}: {source}")]
    Io {
        path: PathBuf,
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// No GPU to render with.
    #[error(transparent)]
    Gpu(#[from] crate::render::gpu::GpuError),
    /// gbm cannot make scanout buffers on this card.
    #[error("{path}: gbm cannot drive the display: {what}: {source}")]
    Gbm {
        path: PathBuf,
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// gbm's buffers cannot be rendered into directly here.
    #[error("{path}: the renderer cannot draw straight into gbm's scanout buffers: {why}")]
    ZeroCopy { path: PathBuf, why: String },
    /// The direct presenter cannot drive this output.
    #[error("{path}: Vulkan cannot drive the display directly: {why}")]
    Direct { path: PathBuf, why: String },
    /// Another program took the display (a VT switch): wait and take it
    /// back.
    #[error("{0}: the display was taken by another program (VT switch)")]
    LostMaster(PathBuf),
    /// Asked to render on a presenter opened to show pictures drawn on
    /// the CPU only.
    #[error("this display was opened to show pictures only; it has no renderer")]
    NoRenderer,
}

/// How a caller answers a display error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorClass {
    /// The display is not ours for now, or a flip was refused for now:
    /// stop drawing and take it back later.
    TryAgain,
    /// The GPU device is gone: make a new one.
    GpuGone,
    /// Nothing the program can do by waiting: stop, saying why.
    Fatal,
}

impl PresentError {
    /// How to answer it.
    #[must_use]
    pub fn class(&self) -> ErrorClass {
        match self {
            Self::LostMaster(_) => ErrorClass::TryAgain,
            Self::Io { source, .. }
                if matches!(
                    source.raw_os_error(),
                    Some(libc::EINTR | libc::EAGAIN | libc::EBUSY)
                ) =>
            {
                ErrorClass::TryAgain
            }
            Self::Gpu(crate::render::gpu::GpuError::Lost(_)) => ErrorClass::GpuGone,
            _ => ErrorClass::Fatal,
        }
    }
}

/// RGBA rows into XRGB8888 (little-endian B, G, R, X) rows of `pitch`
/// bytes; what does not fit is cut, what is missing stays black.
pub fn copy_rgba_to_xrgb(img: &Image, dst: &mut [u8], pitch: usize, width: u32, height: u32) {
    let w = width.min(img.width) as usize;
    for y in 0..height.min(img.height) as usize {
        let src = &img.rgba[y * img.width as usize * 4..][..w * 4];
        let Some(row) = dst.get_mut(y * pitch..y * pitch + w * 4) else {
            break;
        };
        for (d, s) in row.chunks_exact_mut(4).zip(src.chunks_exact(4)) {
            d[0] = s[2];
            d[1] = s[1];
            d[2] = s[0];
            d[3] = 0xff;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_sorted_by_how_they_are_answered() {
        let io = |errno| PresentError::Io {
            path: PathBuf::from("/dev/dri/card0"),
            what: "page flip",
            source: std::io::Error::from_raw_os_error(errno),
        };
        assert_eq!(
            PresentError::LostMaster(PathBuf::from("/dev/dri/card0")).class(),
            ErrorClass::TryAgain
        );
        assert_eq!(io(libc::EBUSY).class(), ErrorClass::TryAgain);
        assert_eq!(io(libc::EINTR).class(), ErrorClass::TryAgain);
        assert_eq!(io(libc::ENODEV).class(), ErrorClass::Fatal);
        assert_eq!(
            PresentError::Gpu(crate::render::gpu::GpuError::Lost("device lost".into())).class(),
            ErrorClass::GpuGone
        );
        // Misuse is no lost GPU: rebuilding it would not help.
        assert_eq!(PresentError::NoRenderer.class(), ErrorClass::Fatal);
        assert_eq!(
            PresentError::NoOutput("no connector".into()).class(),
            ErrorClass::Fatal
        );
    }

    #[test]
    fn rgba_becomes_xrgb_with_the_pitch() {
        let img = Image {
            width: 2,
            height: 2,
            rgba: vec![
                1, 2, 3, 4, 5, 6, 7, 8, //
                9, 10, 11, 12, 13, 14, 15, 16,
            ],
        };
        let mut dst = vec![0u8; 3 * 12];
        copy_rgba_to_xrgb(&img, &mut dst, 12, 3, 3);
        assert_eq!(&dst[0..8], &[3, 2, 1, 255, 7, 6, 5, 255]);
        assert_eq!(&dst[8..12], &[0, 0, 0, 0], "beyond the image stays black");
        assert_eq!(&dst[12..20], &[11, 10, 9, 255, 15, 14, 13, 255]);
        assert!(dst[24..].iter().all(|b| *b == 0));
    }
}

//! The KMS output behind one interface, whichever of four presenters
//! drives it: direct (Vulkan renders into the display's swapchain), gbm
//! zero copy (rendered straight into gbm's scanout buffers where the
//! Vulkan driver imports them), gbm (rendered offscreen and written into
//! them) or copy (the same into dumb buffers). `auto` tries direct, then gbm zero-copy, then gbm,
//! then copy, and the journal says which and why each earlier one was
//! refused.

use std::os::fd::BorrowedFd;
use std::path::Path;
use std::time::Duration;

use super::direct::DirectPresenter;
use super::present::{Attempt, CopyPresenter, OutputChoice, PresentError, PresenterKind, Via};
use crate::render::gpu::{AdapterChoice, Gpu};
use crate::render::headless::{Headless, Image};
use crate::render::mesh::DrawList;

/// What drives the output: one of four presenters, each said as what it
/// is.
pub enum Presenter {
    /// Vulkan drives the display (`VK_EXT_acquire_drm_display`): frames
    /// are rendered into its swapchain.
    Direct(Box<DirectPresenter>),
    /// The renderer draws straight into gbm's scanout buffers.
    GbmZeroCopy(Box<CopyPresenter>),
    /// Frames rendered offscreen written into gbm's scanout buffers.
    GbmWritten(Box<Written>),
    /// Frames rendered offscreen written into dumb buffers (every KMS
    /// driver has them).
    Dumb(Box<Written>),
}

/// A presenter frames are written into: the output's buffers, and the
/// offscreen renderer (`None` where only pictures drawn on the CPU are
/// shown: `marionette calibrate`).
pub struct Written {
    buffers: CopyPresenter,
    headless: Option<Headless>,
}

impl Presenter {
    /// The KMS output's buffers, for the three presenters that flip them.
    fn kms(&self) -> Option<&CopyPresenter> {
        match self {
            Self::Direct(_) => None,
            Self::GbmZeroCopy(p) => Some(p),
            Self::GbmWritten(w) | Self::Dumb(w) => Some(&w.buffers),
        }
    }

    fn kms_mut(&mut self) -> Option<&mut CopyPresenter> {
        match self {
            Self::Direct(_) => None,
            Self::GbmZeroCopy(p) => Some(p),
            Self::GbmWritten(w) | Self::Dumb(w) => Some(&mut w.buffers),
        }
    }

    /// Its name in the journal.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            Self::Direct(_) => "direct",
            Self::GbmZeroCopy(_) => "gbm, zero copy",
            Self::GbmWritten(_) => "gbm",
            Self::Dumb(_) => "copy",
        }
    }
}

/// An output being driven, and how to open it again.
pub struct Screen {
    pub presenter: Presenter,
    adapter: AdapterChoice,
    samples: u32,
}

impl Screen {
    /// Open the output `choice` names on the cards in `dir` with the
    /// presenter `kind` asks for (`Auto`: direct where the Vulkan driver
    /// can, else copy).
    pub fn open(
        dir: &Path,
        choice: &OutputChoice,
        kind: PresenterKind,
        adapter: AdapterChoice,
        samples: u32,
    ) -> Result<Self, PresentError> {
        Self::open_with(dir, choice, kind, Some(adapter), samples)
    }

    /// Open the output to show pictures drawn on the CPU only
    /// ([`Screen::show_image`]): the copy presenter then needs no GPU.
    pub fn open_for_pictures(
        dir: &Path,
        choice: &OutputChoice,
        kind: PresenterKind,
    ) -> Result<Self, PresentError> {
        Self::open_with(dir, choice, kind, None, 1)
    }

    fn open_with(
        dir: &Path,
        choice: &OutputChoice,
        kind: PresenterKind,
        renderer: Option<AdapterChoice>,
        samples: u32,
    ) -> Result<Self, PresentError> {
        let adapter = renderer.unwrap_or_default();
        let attempts = kind.attempts(adapter == AdapterChoice::Cpu);
        let why = match kind {
            PresenterKind::Auto if adapter == AdapterChoice::Cpu => {
                "chosen automatically; rendering on the CPU was asked for, which only a copy presenter can show"
            }
            PresenterKind::Auto => "chosen automatically",
            _ => "as configured",
        };
        let mut presenter = None;
        for (n, attempt) in attempts.iter().enumerate() {
            let opened = match attempt {
                Attempt::Direct => DirectPresenter::open(dir, choice, samples)
                    .map(|d| Presenter::Direct(Box::new(d))),
                // Only a renderer draws into the buffers: pictures drawn on
                // the CPU are written into them.
                Attempt::GbmZeroCopy => match renderer {
                    Some(adapter) => Self::copy(
                        dir,
                        choice,
                        None,
                        samples,
                        Via::GbmZeroCopy { adapter, samples },
                    ),
                    None => Self::copy(dir, choice, None, samples, Via::Gbm),
                },
                Attempt::Gbm => Self::copy(dir, choice, renderer, samples, Via::Gbm),
                Attempt::Dumb => Self::copy(dir, choice, renderer, samples, Via::Dumb),
            };
            match opened {
                Ok(p) => {
                    match &p {
                        Presenter::GbmZeroCopy(z) => tracing::info!(
                            samples = z.samples().unwrap_or(1),
                            "presenter: {} ({why})",
                            p.name()
                        ),
                        _ => tracing::info!("presenter: {} ({why})", p.name()),
                    }
                    presenter = Some(p);
                    break;
                }
                // No display, or another program's: no presenter helps.
                Err(e @ (PresentError::NoOutput(_) | PresentError::Master { .. })) => {
                    return Err(e);
                }
                Err(e) if n + 1 == attempts.len() => return Err(e),
                Err(e) => {
                    tracing::info!(reason = %e, "the {} presenter is not available here", attempt.name());
                }
            }
        }
        let Some(presenter) = presenter else {
            return Err(PresentError::NoOutput("no presenter to try".to_owned()));
        };
        Ok(Self {
            presenter,
            adapter,
            samples,
        })
    }

    fn copy(
        dir: &Path,
        choice: &OutputChoice,
        renderer: Option<AdapterChoice>,
        samples: u32,
        via: Via,
    ) -> Result<Presenter, PresentError> {
        let buffers = CopyPresenter::open(dir, choice, via)?;
        if buffers.renders() {
            return Ok(Presenter::GbmZeroCopy(Box::new(buffers)));
        }
        let (w, h) = buffers.size();
        let headless = match renderer {
            Some(adapter) => {
                let headless = Headless::new(Gpu::new(adapter)?, w, h, samples)?;
                tracing::info!(
                    width = w,
                    height = h,
                    samples = headless.renderer.samples(),
                    "rendering offscreen"
                );
                Some(headless)
            }
            None => None,
        };
        let written = Box::new(Written { buffers, headless });
        Ok(match via {
            Via::Dumb => Presenter::Dumb(written),
            Via::Gbm | Via::GbmZeroCopy { .. } => Presenter::GbmWritten(written),
        })
    }

    /// The output's size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        match &self.presenter {
            Presenter::Direct(d) => d.size(),
            p => p.kms().map_or((0, 0), CopyPresenter::size),
        }
    }

    /// The connector's name.
    #[must_use]
    pub fn name(&self) -> &str {
        match &self.presenter {
            Presenter::Direct(d) => d.name(),
            p => p.kms().map_or("", CopyPresenter::name),
        }
    }

    /// The refresh rate (Hz).
    #[must_use]
    pub fn refresh_hz(&self) -> u32 {
        match &self.presenter {
            Presenter::Direct(d) => d.refresh_hz(),
            p => p.kms().map_or(60, CopyPresenter::refresh_hz),
        }
    }

    /// Frames shown (page flips, or frames queued to the swapchain).
    #[must_use]
    pub fn flips(&self) -> u64 {
        match &self.presenter {
            Presenter::Direct(d) => d.flips(),
            p => p.kms().map_or(0, CopyPresenter::flips),
        }
    }

    /// Whether a flip is queued that the next frame must wait for (the
    /// swapchain paces the direct presenter itself).
    #[must_use]
    pub fn flip_pending(&self) -> bool {
        self.presenter
            .kms()
            .is_some_and(CopyPresenter::flip_pending)
    }

    /// The descriptor that becomes readable when a flip completed.
    #[must_use]
    pub fn fd(&self) -> Option<BorrowedFd<'_>> {
        self.presenter.kms().map(CopyPresenter::fd)
    }

    /// Read the display's events: whether a flip completed.
    pub fn dispatch(&mut self) -> Result<bool, PresentError> {
        self.presenter
            .kms_mut()
            .map_or(Ok(false), CopyPresenter::dispatch)
    }

    /// Wait up to `timeout` until the last frame is on screen: whether it
    /// is.
    pub fn wait_flip(&mut self, timeout: Duration) -> Result<bool, PresentError> {
        match &mut self.presenter {
            Presenter::Direct(d) => {
                let _ = d.gpu.device.poll(wgpu::PollType::Wait {
                    submission_index: None,
                    timeout: Some(timeout),
                });
                Ok(d.flips() > 0)
            }
            p => p.kms_mut().map_or(Ok(false), |k| k.wait_flip(timeout)),
        }
    }

    /// Draw `list` and show it at the next vblank. Whether a frame went out
    /// (the direct presenter skips one while its swapchain is rebuilt).
    /// A rendering failure is [`PresentError::Gpu`]: [`Screen::rebuild`];
    /// a presenter opened for pictures only has no renderer
    /// ([`PresentError::NoRenderer`]).
    pub fn draw(&mut self, list: &DrawList) -> Result<bool, PresentError> {
        match &mut self.presenter {
            Presenter::Direct(d) => d.draw(list),
            Presenter::GbmZeroCopy(z) => {
                z.draw(list)?;
                Ok(true)
            }
            Presenter::GbmWritten(w) | Presenter::Dumb(w) => {
                let headless = w.headless.as_mut().ok_or(PresentError::NoRenderer)?;
                let img = headless.render(list)?;
                w.buffers.present(&img)?;
                Ok(true)
            }
        }
    }

    /// Show a picture drawn on the CPU (RGBA, the output's size).
    pub fn show_image(&mut self, img: &Image) -> Result<(), PresentError> {
        match &mut self.presenter {
            Presenter::Direct(d) => d.show_image(img),
            p => p.kms_mut().map_or(Ok(()), |k| k.present(img)),
        }
    }

    /// Take the display back after a VT switch: whether it is ours again.
    pub fn reacquire(&mut self) -> bool {
        match &mut self.presenter {
            Presenter::Direct(d) => d.reacquire(),
            p => p.kms_mut().is_some_and(CopyPresenter::reacquire),
        }
    }

    /// A new GPU device after the old one was lost: the renderer drawing
    /// into gbm's buffers, or the offscreen renderer, again; the whole
    /// output for the direct presenter.
    pub fn rebuild(&mut self) -> Result<(), PresentError> {
        match &mut self.presenter {
            Presenter::Direct(d) => d.rebuild_gpu()?,
            Presenter::GbmZeroCopy(z) => z.rebuild_gpu(self.adapter)?,
            Presenter::GbmWritten(w) | Presenter::Dumb(w) => {
                let (w_px, h_px) = w.buffers.size();
                w.headless = Some(Headless::new(
                    Gpu::new(self.adapter)?,
                    w_px,
                    h_px,
                    self.samples,
                )?);
            }
        }
        Ok(())
    }
}

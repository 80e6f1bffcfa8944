//! The KMS output behind one interface, whichever presenter drives it:
//! direct (Vulkan renders into the display's swapchain), gbm (rendered
//! straight into gbm's scanout buffers where the Vulkan driver imports
//! them, else rendered offscreen and written into them) or copy (the same
//! into dumb buffers). `auto` tries direct, then gbm zero-copy, then gbm,
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

/// What drives the output.
pub enum Presenter {
    Direct(Box<DirectPresenter>),
    Copy {
        presenter: Box<CopyPresenter>,
        /// The offscreen renderer; `None` where only pictures drawn on the
        /// CPU are shown (`marionette calibrate`).
        headless: Option<Box<Headless>>,
    },
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
                    match attempt {
                        Attempt::Direct => tracing::info!("presenter: direct ({why})"),
                        Attempt::GbmZeroCopy if renderer.is_some() => {
                            let samples = match &p {
                                Presenter::Copy { presenter, .. } => presenter.samples(),
                                Presenter::Direct(_) => None,
                            };
                            tracing::info!(
                                samples = samples.unwrap_or(1),
                                "presenter: gbm, zero copy ({why})"
                            );
                        }
                        Attempt::GbmZeroCopy | Attempt::Gbm => {
                            tracing::info!("presenter: gbm ({why})");
                        }
                        Attempt::Dumb => tracing::info!("presenter: copy ({why})"),
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
        let presenter = Box::new(CopyPresenter::open(dir, choice, via)?);
        let (w, h) = presenter.size();
        let headless = match renderer {
            Some(adapter) => {
                let headless = Headless::new(Gpu::new(adapter)?, w, h, samples)?;
                tracing::info!(
                    width = w,
                    height = h,
                    samples = headless.renderer.samples(),
                    "rendering offscreen"
                );
                Some(Box::new(headless))
            }
            None => None,
        };
        Ok(Presenter::Copy {
            presenter,
            headless,
        })
    }

    /// The output's size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        match &self.presenter {
            Presenter::Direct(d) => d.size(),
            Presenter::Copy { presenter, .. } => presenter.size(),
        }
    }

    /// The connector's name.
    #[must_use]
    pub fn name(&self) -> &str {
        match &self.presenter {
            Presenter::Direct(d) => d.name(),
            Presenter::Copy { presenter, .. } => presenter.name(),
        }
    }

    /// The refresh rate (Hz).
    #[must_use]
    pub fn refresh_hz(&self) -> u32 {
        match &self.presenter {
            Presenter::Direct(d) => d.refresh_hz(),
            Presenter::Copy { presenter, .. } => presenter.refresh_hz(),
        }
    }

    /// Frames shown (page flips, or frames queued to the swapchain).
    #[must_use]
    pub fn flips(&self) -> u64 {
        match &self.presenter {
            Presenter::Direct(d) => d.flips(),
            Presenter::Copy { presenter, .. } => presenter.flips(),
        }
    }

    /// Whether a flip is queued that the next frame must wait for (the
    /// swapchain paces the direct presenter itself).
    #[must_use]
    pub fn flip_pending(&self) -> bool {
        match &self.presenter {
            Presenter::Direct(_) => false,
            Presenter::Copy { presenter, .. } => presenter.flip_pending(),
        }
    }

    /// The descriptor that becomes readable when a flip completed.
    #[must_use]
    pub fn fd(&self) -> Option<BorrowedFd<'_>> {
        match &self.presenter {
            Presenter::Direct(_) => None,
            Presenter::Copy { presenter, .. } => Some(presenter.fd()),
        }
    }

    /// Read the display's events: whether a flip completed.
    pub fn dispatch(&mut self) -> Result<bool, PresentError> {
        match &mut self.presenter {
            Presenter::Direct(_) => Ok(false),
            Presenter::Copy { presenter, .. } => presenter.dispatch(),
        }
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
            Presenter::Copy { presenter, .. } => presenter.wait_flip(timeout),
        }
    }

    /// Draw `list` and show it at the next vblank. Whether a frame went out
    /// (the direct presenter skips one while its swapchain is rebuilt).
    /// A rendering failure is [`PresentError::Gpu`]: [`Screen::rebuild`].
    pub fn draw(&mut self, list: &DrawList) -> Result<bool, PresentError> {
        match &mut self.presenter {
            Presenter::Direct(d) => d.draw(list),
            Presenter::Copy { presenter, .. } if presenter.renders() => {
                presenter.draw(list)?;
                Ok(true)
            }
            Presenter::Copy {
                presenter,
                headless,
            } => {
                let headless = headless.as_mut().ok_or_else(|| {
                    crate::render::gpu::GpuError::Lost("opened for pictures only".to_owned())
                })?;
                let img = headless.render(list)?;
                presenter.present(&img)?;
                Ok(true)
            }
        }
    }

    /// Show a picture drawn on the CPU (RGBA, the output's size).
    pub fn show_image(&mut self, img: &Image) -> Result<(), PresentError> {
        match &mut self.presenter {
            Presenter::Direct(d) => d.show_image(img),
            Presenter::Copy { presenter, .. } => presenter.present(img),
        }
    }

    /// Take the display back after a VT switch: whether it is ours again.
    pub fn reacquire(&mut self) -> bool {
        match &mut self.presenter {
            Presenter::Direct(d) => d.reacquire(),
            Presenter::Copy { presenter, .. } => presenter.reacquire(),
        }
    }

    /// A new GPU device after the old one was lost: the renderer again for
    /// the copy presenter, the whole output for the direct one.
    pub fn rebuild(&mut self) -> Result<(), PresentError> {
        match &mut self.presenter {
            Presenter::Copy { presenter, .. } if presenter.renders() => {
                presenter.rebuild_gpu(self.adapter)?;
            }
            Presenter::Copy {
                presenter,
                headless,
            } => {
                let (w, h) = presenter.size();
                *headless = Some(Box::new(Headless::new(
                    Gpu::new(self.adapter)?,
                    w,
                    h,
                    self.samples,
                )?));
            }
            Presenter::Direct(d) => d.rebuild_gpu()?,
        }
        Ok(())
    }
}

//! Screenshots of the primary window: once when the scene is ready ([`AutoScreenshot`]), or on
//! demand ([`capture_and_exit`]).

use super::*;

/// A screenshot of the primary window, taken once `ready` is set and `settle_frames` more frames
/// have been drawn; the app exits when the file is written.
#[derive(Resource, Debug, Clone)]
pub struct AutoScreenshot {
    /// Where the PNG goes.
    pub path: PathBuf,
    /// Set by the owner when the scene is ready.
    pub ready: bool,
    /// Frames to draw after `ready` before capturing (egui and textures need a few).
    pub settle_frames: u32,
    settled: u32,
    requested: bool,
}

impl AutoScreenshot {
    /// A screenshot to `path`, not ready yet, 5 settle frames.
    pub fn new(path: impl Into<PathBuf>) -> AutoScreenshot {
        AutoScreenshot { path: path.into(), ready: false, settle_frames: 5, settled: 0, requested: false }
    }
}

pub(super) fn auto_screenshot(mut commands: Commands, mut shot: ResMut<AutoScreenshot>) {
    if !shot.ready || shot.requested {
        return;
    }
    shot.settled += 1;
    if shot.settled > shot.settle_frames {
        shot.requested = true;
        capture_and_exit(&mut commands, shot.path.clone());
    }
}

/// Captures the primary window to a PNG at `path`, then exits (with an error code if the file
/// cannot be written).
pub fn capture_and_exit(commands: &mut Commands, path: PathBuf) {
    commands.spawn(Screenshot::primary_window()).observe(
        move |captured: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| match save_png(
            &captured.image,
            &path,
        ) {
            Ok(()) => {
                println!("screenshot saved to {}", path.display());
                exit.write(AppExit::Success);
            }
            Err(e) => {
                eprintln!("cannot save the screenshot to {}: {e}", path.display());
                exit.write(AppExit::error());
            }
        },
    );
}

fn save_png(image: &Image, path: &Path) -> Result<(), String> {
    let rgb = image.clone().try_into_dynamic().map_err(|e| e.to_string())?.to_rgb8();
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    }
    rgb.save(path).map_err(|e| e.to_string())
}

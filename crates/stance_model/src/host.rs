//! What the editor needs from the page (or the native shell) and what the page tells it.
//! The browser implements [`HostHooks`] in `stance_web` with `localStorage`, the address bar,
//! downloads and a file picker; native shells and tests use [`MemoryHost`].

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::rc::Rc;

use crate::jobs::JobRequest;
use crate::sensors::SensorConnection;

/// The graphics backend and adapter the viewport runs on, as the status bar names them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BackendSummary {
    /// "WebGPU", "WebGL2", "Vulkan", ...
    pub backend: String,
    /// The adapter's name as the driver reports it.
    pub adapter: String,
}

/// An avatar file for the host to import off the editor's thread
/// ([`HostHooks::import_avatar`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AvatarImport {
    /// The file's name or URL; the reply names it.
    pub name: String,
    /// The file's contents (GLB, glTF, VRM).
    pub bytes: Vec<u8>,
    /// The files a `.gltf` refers to (`.bin` buffers, images), by name.
    pub resources: Vec<(String, Vec<u8>)>,
}

/// An avatar the host imported ([`HostMessage::AvatarImported`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedAvatar {
    /// The imported file.
    pub avatar: stance_asset::Avatar,
    /// How long the import took where it ran, in ms.
    pub import_ms: f64,
    /// Whether it was imported off the editor's thread (the page's loading worker).
    pub in_worker: bool,
    /// How long handing it to the editor's thread took (decoding the transfer), in ms.
    pub transfer_ms: f64,
    /// Texture images the host's own decoders decoded for it.
    pub images_from_host: usize,
}

/// What the editor asks of its host. Every method but the first has a do-nothing default.
pub trait HostHooks {
    /// Called once, after the first frame with the 3D scene has been rendered.
    fn first_frame_rendered(&self, backend: &BackendSummary);

    /// Durable text by key (the browser's `localStorage`); `None` when absent or unavailable.
    fn load_text(&self, _key: &str) -> Option<String> {
        None
    }

    /// Stores durable text; an error says why it could not (quota, private mode...).
    fn save_text(&self, _key: &str, _text: &str) -> Result<(), String> {
        Err("this shell has no storage".to_owned())
    }

    /// Puts the posture link's fragment in the address bar (without reloading) and returns
    /// the whole link to share.
    fn share_link(&self, fragment: &str) -> String {
        format!("#{fragment}")
    }

    /// Offers `text` as a file download named `file_name`.
    fn download(&self, _file_name: &str, _text: &str) -> Result<(), String> {
        Err("this shell cannot download files".to_owned())
    }

    /// Opens the file picker; the chosen file arrives as [`HostMessage::OpenFile`].
    fn pick_file(&self) -> Result<(), String> {
        Err("this shell has no file picker".to_owned())
    }

    /// An avatar's upload to the GPU began: the host may step it in tasks of its own
    /// (`StanceApp::upload_avatar_task` until it returns false), between frames, and return
    /// true; false (the default): the frames step it. In a browser, frames that repaint a
    /// software-composited canvas are slow to come while a large avatar arrives.
    fn upload_in_tasks(&self) -> bool {
        false
    }

    /// Opens a picker for a photo, decodes it and finds the person in it with the host's pose
    /// detector (the page: MediaPipe Pose in a worker); the result arrives as
    /// [`HostMessage::PhotoDetected`], a failure (not an image, no person found) as
    /// [`HostMessage::PhotoFailed`].
    fn pick_photo(&self) -> Result<(), String> {
        Err("this shell has no pose detector: photos open in the browser".to_owned())
    }

    /// Fetches `url` (an avatar); the bytes arrive as [`HostMessage::OpenFile`] named by the
    /// URL, a failure as [`HostMessage::Failed`].
    fn fetch(&self, _url: &str) -> Result<(), String> {
        Err("this shell cannot fetch files".to_owned())
    }

    /// Opens a sensor device: a serial port or a HID device (the browser asks the user which).
    /// What follows arrives as [`HostMessage::SensorConnected`], [`HostMessage::SensorBytes`],
    /// [`HostMessage::SensorReport`] and [`HostMessage::SensorLost`].
    fn connect_sensor(&self, _request: &SensorConnection) -> Result<(), String> {
        Err("this shell has no serial or HID access; replay a recording instead".to_owned())
    }

    /// Closes the sensor device, if one is open.
    fn disconnect_sensor(&self) {}

    /// Offers `bytes` as a file download named `file_name` (sensor recordings, posed GLB).
    fn download_bytes(&self, _file_name: &str, _bytes: &[u8]) -> Result<(), String> {
        Err("this shell cannot download files".to_owned())
    }

    /// Imports an avatar file off the editor's thread (the page's import worker), so that a
    /// large file does not hold up the frames; the result arrives as
    /// [`HostMessage::AvatarImported`]. Gives the request back when this host cannot: the
    /// editor then imports it itself.
    fn import_avatar(&self, request: AvatarImport) -> Result<(), AvatarImport> {
        Err(request)
    }

    /// Runs a job off the editor's thread (the page's loading worker): a clip file read and
    /// retargeted in steps, keypoints lifted, so that they do not hold up the frames; a
    /// clip's progress arrives as [`HostMessage::JobProgress`], the result as
    /// [`HostMessage::ClipOpened`] or [`HostMessage::KeypointsLifted`], a failure of either
    /// as [`HostMessage::JobFailed`]. Gives the request back when this host cannot: the
    /// editor then does it itself.
    fn run_job(&self, request: JobRequest) -> Result<(), JobRequest> {
        Err(request)
    }

    /// Stops the job `id` ([`HostHooks::run_job`]): nothing more of it arrives (a reply
    /// already on its way is ignored by its id).
    fn cancel_job(&self, _id: u64) {}
}

/// What the host tells the editor, through the sender given to `StanceApp::with_inbox`.
#[derive(Debug, Clone, PartialEq)]
pub enum HostMessage {
    /// A posture link was opened (the address bar's fragment changed).
    OpenLink(String),
    /// The user picked or dropped a file.
    OpenFile {
        /// The file's name, or the URL it was fetched from.
        name: String,
        /// The file's contents.
        bytes: Vec<u8>,
    },
    /// Files picked or dropped together (name, contents), e.g. a `.gltf` with its `.bin`
    /// and images.
    OpenFiles(Vec<(String, Vec<u8>)>),
    /// The texture images of the avatar file `file`, decoded by the host (the browser, off the
    /// main thread): its import that follows takes them as they are.
    DecodedImages {
        /// The file (name or URL) the images belong to.
        file: String,
        /// The images' pixels.
        images: Vec<stance_asset::DecodedImage>,
    },
    /// The host failed to do what the editor asked (reading a file...).
    Failed(String),
    /// The avatar asked for with [`HostHooks::import_avatar`], or why it could not be
    /// imported.
    AvatarImported {
        /// The file's name or URL, as asked.
        name: String,
        /// The avatar, or what is wrong with the file.
        result: Result<Box<ImportedAvatar>, String>,
    },
    /// How far the job `id` ([`HostHooks::run_job`]) has got.
    JobProgress {
        /// The request.
        id: u64,
        /// From 0 to 1.
        fraction: f64,
    },
    /// The clip asked for with [`HostHooks::run_job`], read and retargeted, or what is
    /// wrong with it (in words).
    ClipOpened {
        /// The request.
        id: u64,
        /// The clip and its retargeting, or why not.
        result: Result<Box<stance_asset::OpenedClip>, String>,
    },
    /// The keypoints asked for with [`HostHooks::run_job`] lifted (a scene of a character
    /// per person, or a flip's one character), or what is wrong with them (in words).
    KeypointsLifted {
        /// The request.
        id: u64,
        /// The lifted scene, or why not.
        result: Result<Box<stance_document::Scene>, String>,
    },
    /// The person the host's pose detector found in the photo the user picked
    /// ([`HostHooks::pick_photo`]).
    PhotoDetected(Box<crate::model::photo::DetectedPhoto>),
    /// The photo `name` could not be opened: `reason` says why (not an image, no person
    /// found, the detector could not start).
    PhotoFailed {
        /// The file's name.
        name: String,
        /// What went wrong, in words.
        reason: String,
    },
    /// The job `id` ([`HostHooks::run_job`]) failed where it ran: `reason` says why.
    JobFailed {
        /// The request.
        id: u64,
        /// What went wrong, in words.
        reason: String,
    },
    /// The sensor device is open.
    SensorConnected {
        /// The device's name as the browser gives it.
        device: String,
    },
    /// Bytes from the serial sensor device.
    SensorBytes {
        /// The bytes as read, in order (a line may be split across messages).
        bytes: Vec<u8>,
        /// When the page received them.
        arrived: web_time::Instant,
    },
    /// One input report from the HID sensor device.
    SensorReport {
        /// The HID report ID (0 when the device uses none).
        report_id: u8,
        /// The report's bytes, without the report ID.
        data: Vec<u8>,
        /// When the page received it.
        arrived: web_time::Instant,
    },
    /// The sensor device went away or failed (unplugged, permission refused, read error).
    SensorLost {
        /// What happened, for the user.
        reason: String,
    },
}

/// Hooks that do nothing: the native shell.
#[derive(Debug, Default)]
pub struct NoHostHooks;

impl HostHooks for NoHostHooks {
    fn first_frame_rendered(&self, _backend: &BackendSummary) {}
}

/// A host that keeps everything in memory, shared through `Rc` so that a test can look at
/// what the editor stored and downloaded.
#[derive(Debug, Default, Clone)]
pub struct MemoryHost {
    /// What the editor stored, downloaded and asked for.
    pub inner: Rc<RefCell<MemoryHostState>>,
}

impl MemoryHost {
    /// The durable texts the editor stored (the autosave, the library), in key order.
    pub fn stored_texts(&self) -> Vec<String> {
        self.inner.borrow().storage.values().cloned().collect()
    }
}

/// The contents of a [`MemoryHost`].
#[derive(Debug, Default)]
pub struct MemoryHostState {
    /// The durable text by key (what `localStorage` would hold).
    pub storage: BTreeMap<String, String>,
    /// The text downloads offered, in order: file name and contents.
    pub downloads: Vec<(String, String)>,
    /// The last posture link fragment put in the address bar.
    pub address_fragment: Option<String>,
    /// How many times the file picker was opened.
    pub file_requests: usize,
    /// How many times a photo was asked for ([`HostHooks::pick_photo`]).
    pub photo_requests: usize,
    /// The URLs asked for, in order.
    pub fetches: Vec<String>,
    /// The backend reported after the first rendered frame; `None` before it.
    pub first_frame: Option<BackendSummary>,
    /// The sensor connections asked for, in order.
    pub sensor_requests: Vec<SensorConnection>,
    /// How many times the sensor device was closed.
    pub sensor_disconnects: usize,
    /// The binary downloads offered, in order: file name and contents.
    pub binary_downloads: Vec<(String, Vec<u8>)>,
    /// Whether it takes avatar imports ([`HostHooks::import_avatar`]; default no).
    pub imports_avatars: bool,
    /// The avatar imports it took, in order (a test answers them).
    pub avatar_imports: Vec<AvatarImport>,
    /// Whether it takes jobs ([`HostHooks::run_job`]; default no).
    pub runs_jobs: bool,
    /// The jobs it took, in order (a test answers them).
    pub jobs: Vec<JobRequest>,
    /// The jobs cancelled, in order.
    pub cancelled_jobs: Vec<u64>,
}

impl HostHooks for MemoryHost {
    fn first_frame_rendered(&self, backend: &BackendSummary) {
        self.inner.borrow_mut().first_frame = Some(backend.clone());
    }

    fn load_text(&self, key: &str) -> Option<String> {
        self.inner.borrow().storage.get(key).cloned()
    }

    fn save_text(&self, key: &str, text: &str) -> Result<(), String> {
        self.inner
            .borrow_mut()
            .storage
            .insert(key.to_owned(), text.to_owned());
        Ok(())
    }

    fn share_link(&self, fragment: &str) -> String {
        self.inner.borrow_mut().address_fragment = Some(fragment.to_owned());
        format!("http://localhost/#{fragment}")
    }

    fn download(&self, file_name: &str, text: &str) -> Result<(), String> {
        self.inner
            .borrow_mut()
            .downloads
            .push((file_name.to_owned(), text.to_owned()));
        Ok(())
    }

    fn pick_file(&self) -> Result<(), String> {
        self.inner.borrow_mut().file_requests += 1;
        Ok(())
    }

    fn pick_photo(&self) -> Result<(), String> {
        self.inner.borrow_mut().photo_requests += 1;
        Ok(())
    }

    fn fetch(&self, url: &str) -> Result<(), String> {
        self.inner.borrow_mut().fetches.push(url.to_owned());
        Ok(())
    }

    fn connect_sensor(&self, request: &SensorConnection) -> Result<(), String> {
        self.inner
            .borrow_mut()
            .sensor_requests
            .push(request.clone());
        Ok(())
    }

    fn disconnect_sensor(&self) {
        self.inner.borrow_mut().sensor_disconnects += 1;
    }

    fn download_bytes(&self, file_name: &str, bytes: &[u8]) -> Result<(), String> {
        self.inner
            .borrow_mut()
            .binary_downloads
            .push((file_name.to_owned(), bytes.to_vec()));
        Ok(())
    }

    fn import_avatar(&self, request: AvatarImport) -> Result<(), AvatarImport> {
        let mut inner = self.inner.borrow_mut();
        if !inner.imports_avatars {
            return Err(request);
        }
        inner.avatar_imports.push(request);
        Ok(())
    }

    fn run_job(&self, request: JobRequest) -> Result<(), JobRequest> {
        let mut inner = self.inner.borrow_mut();
        if !inner.runs_jobs {
            return Err(request);
        }
        inner.jobs.push(request);
        Ok(())
    }

    fn cancel_job(&self, id: u64) {
        self.inner.borrow_mut().cancelled_jobs.push(id);
    }
}

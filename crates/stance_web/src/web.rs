//! Browser glue (wasm32 only). The browser APIs the editor needs (storage, address bar,
//! downloads, file picker) are small functions of `window.stanceHost`, defined by
//! `web/main.js`; this module adapts them to the editor's [`HostHooks`] and feeds what the
//! page receives (links, files) to the editor's inbox.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::mpsc::Sender;

use eframe::wasm_bindgen::{self, prelude::*};
use stance_editor::avatar::LoadedAvatar;
use stance_editor::sensors::SensorConnection;
use stance_editor::{
    AvatarImport, BackendSummary, HostHooks, HostJob, HostMessage, ImportedAvatar, JobRequest,
    StanceApp,
};

use crate::accessibility::{AccessibilityBridge, PageAction, PendingActions};

#[wasm_bindgen]
extern "C" {
    #[wasm_bindgen(js_namespace = stanceHost, js_name = loadText, catch)]
    fn host_load_text(key: &str) -> Result<Option<String>, JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = saveText, catch)]
    fn host_save_text(key: &str, text: &str) -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = shareLink, catch)]
    fn host_share_link(fragment: &str) -> Result<String, JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = download, catch)]
    fn host_download(file_name: &str, text: &str) -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = pickFile, catch)]
    fn host_pick_file() -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = pickPhoto, catch)]
    fn host_pick_photo() -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = fetchFile, catch)]
    fn host_fetch_file(url: &str) -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = downloadBytes, catch)]
    fn host_download_bytes(file_name: &str, bytes: &[u8]) -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = connectSensor, catch)]
    fn host_connect_sensor(request_json: &str) -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = disconnectSensor, catch)]
    fn host_disconnect_sensor() -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = uploadAvatar, catch)]
    fn host_upload_avatar() -> Result<bool, JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = importAvatar, catch)]
    fn host_import_avatar(
        name: &str,
        names: Vec<String>,
        lengths: Vec<u32>,
        bytes: &[u8],
    ) -> Result<bool, JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = runJob, catch)]
    fn host_run_job(kind: &str, id: f64, job: &[u8]) -> Result<bool, JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = cancelJob, catch)]
    fn host_cancel_job(id: f64) -> Result<(), JsValue>;
    #[wasm_bindgen(js_namespace = stanceHost, js_name = accessibility, catch)]
    fn host_accessibility(tree_json: &str) -> Result<(), JsValue>;
}

fn describe(error: &JsValue) -> String {
    error
        .as_string()
        .or_else(|| {
            js_sys::Reflect::get(error, &JsValue::from_str("message"))
                .ok()
                .and_then(|message| message.as_string())
        })
        .unwrap_or_else(|| "the browser refused".to_owned())
}

/// Tells the page about the editor: attributes on `<body>` when the first frame is up
/// (`data-backend`, `data-adapter`, `data-first-frame-ms`), and the browser services behind
/// `window.stanceHost`.
struct PageHooks;

impl HostHooks for PageHooks {
    fn first_frame_rendered(&self, backend: &BackendSummary) {
        let Some(window) = web_sys::window() else {
            return;
        };
        let elapsed_ms = window
            .performance()
            .map_or(0.0, |performance| performance.now());
        let Some(body) = window.document().and_then(|document| document.body()) else {
            return;
        };
        let _ = body.set_attribute("data-backend", &backend.backend);
        let _ = body.set_attribute("data-adapter", &backend.adapter);
        let _ = body.set_attribute("data-first-frame-ms", &format!("{elapsed_ms:.0}"));
        if let Some(loading) = window
            .document()
            .and_then(|document| document.get_element_by_id("loading"))
        {
            let _ = loading.set_attribute("hidden", "");
        }
        log::info!(
            "first frame after {elapsed_ms:.0} ms on {} ({})",
            backend.backend,
            backend.adapter
        );
    }

    fn load_text(&self, key: &str) -> Option<String> {
        host_load_text(key).ok().flatten()
    }

    fn save_text(&self, key: &str, text: &str) -> Result<(), String> {
        host_save_text(key, text).map_err(|error| describe(&error))
    }

    fn share_link(&self, fragment: &str) -> String {
        host_share_link(fragment).unwrap_or_else(|_| format!("#{fragment}"))
    }

    fn download(&self, file_name: &str, text: &str) -> Result<(), String> {
        host_download(file_name, text).map_err(|error| describe(&error))
    }

    fn pick_file(&self) -> Result<(), String> {
        host_pick_file().map_err(|error| describe(&error))
    }

    fn pick_photo(&self) -> Result<(), String> {
        host_pick_photo().map_err(|error| describe(&error))
    }

    fn fetch(&self, url: &str) -> Result<(), String> {
        host_fetch_file(url).map_err(|error| describe(&error))
    }

    fn connect_sensor(&self, request: &SensorConnection) -> Result<(), String> {
        host_connect_sensor(&request.to_json()).map_err(|error| describe(&error))
    }

    fn disconnect_sensor(&self) {
        if let Err(error) = host_disconnect_sensor() {
            log::warn!("closing the sensor device: {}", describe(&error));
        }
    }

    fn download_bytes(&self, file_name: &str, bytes: &[u8]) -> Result<(), String> {
        host_download_bytes(file_name, bytes).map_err(|error| describe(&error))
    }

    fn upload_in_tasks(&self) -> bool {
        host_upload_avatar().unwrap_or_else(|error| {
            log::warn!(
                "the page cannot step the avatar's upload: {}",
                describe(&error)
            );
            false
        })
    }

    fn import_avatar(&self, request: AvatarImport) -> Result<(), AvatarImport> {
        // The file first, then its resources, one after the other.
        let mut names = vec![request.name.clone()];
        let mut lengths = vec![u32::try_from(request.bytes.len()).unwrap_or(u32::MAX)];
        let mut bytes = request.bytes.clone();
        for (name, part) in &request.resources {
            names.push(name.clone());
            lengths.push(u32::try_from(part.len()).unwrap_or(u32::MAX));
            bytes.extend_from_slice(part);
        }
        match host_import_avatar(&request.name, names, lengths, &bytes) {
            Ok(true) => Ok(()),
            Ok(false) => Err(request),
            Err(error) => {
                log::warn!("the import worker refused the avatar: {}", describe(&error));
                Err(request)
            }
        }
    }

    fn run_job(&self, request: JobRequest) -> Result<(), JobRequest> {
        // The job as bytes for the page's loading worker (a clip: the file, the body, the
        // settings; a lift: the keypoints or the document); a page that cannot take it gives
        // the request back.
        let Ok(job) = request.job.to_bytes() else {
            return Err(request);
        };
        match host_run_job(request.job.kind(), request.id as f64, &job) {
            Ok(true) => Ok(()),
            Ok(false) => Err(request),
            Err(error) => {
                log::warn!("the page could not run the job: {}", describe(&error));
                Err(request)
            }
        }
    }

    fn cancel_job(&self, id: u64) {
        if let Err(error) = host_cancel_job(id as f64) {
            log::warn!("cancelling the job: {}", describe(&error));
        }
    }
}

/// Runs in the page's loading worker (`web/load-worker.js`), not in the editor: imports the
/// avatar file `names[0]` with the other files as its resources, the texture images the page
/// decoded (as [`WebHandle::decoded_images`] takes them) and, without their pixels, the images
/// `to_follow` the page is decoding meanwhile (`stance_asset::HostImages::to_follow`), and
/// returns it split for the trip (`stance_asset::AvatarTransfer`): `[avatar bytes, textures,
/// pixels of texture 0, ...]`, for [`WebHandle::avatar_texture`] and
/// [`WebHandle::avatar_imported`]. `textures` holds three numbers per texture: its image's
/// index (`u32::MAX`: none), width and height; a texture whose pixels follow has empty
/// pixels here, for the page to fill. Throws what is wrong with the file.
#[wasm_bindgen]
#[allow(clippy::too_many_arguments)]
pub fn import_avatar_file(
    names: Vec<String>,
    lengths: Vec<u32>,
    bytes: Vec<u8>,
    indices: Vec<u32>,
    widths: Vec<u32>,
    heights: Vec<u32>,
    rgba: Vec<u8>,
    to_follow: Vec<u32>,
) -> Result<js_sys::Array, String> {
    let parts = split_by_lengths(&bytes, lengths.iter().map(|&n| Some(n as usize)))
        .filter(|parts| parts.len() == names.len() && !parts.is_empty())
        .ok_or("the files could not be read together")?;
    let mut files = names.into_iter().zip(parts);
    let (_, main) = files.next().ok_or("no file")?;
    let resources: Vec<(String, Vec<u8>)> =
        files.map(|(name, part)| (name, part.to_vec())).collect();
    let images = stance_asset::HostImages {
        decoded: decoded_images(&indices, &widths, &heights, &rgba).unwrap_or_default(),
        to_follow: to_follow.iter().map(|&i| i as usize).collect(),
    };
    let imported = LoadedAvatar::import(main, &resources, images)?;
    let textures: Vec<u32> = imported
        .avatar
        .textures
        .iter()
        .flat_map(|t| {
            let image = t.image.and_then(|i| u32::try_from(i).ok());
            [image.unwrap_or(u32::MAX), t.width, t.height]
        })
        .collect();
    let transfer =
        stance_asset::AvatarTransfer::new(imported.avatar).map_err(|error| error.to_string())?;
    let out = js_sys::Array::new();
    out.push(&js_sys::Uint8Array::from(transfer.avatar.as_slice()));
    out.push(&js_sys::Uint32Array::from(textures.as_slice()));
    for part in &transfer.pixels {
        out.push(&js_sys::Uint8Array::from(part.as_slice()));
    }
    Ok(out)
}

/// Runs a job in the page's loading worker: `job` is the request the editor gave the page
/// (`stanceHost.runJob`: `stance_editor::HostJob` as bytes, a clip to read and retarget or
/// keypoints to lift); `progress` is called with the fraction done between steps. Returns the
/// result split for the trip (`stance_editor::HostJob::run_for_transfer`): `[head, part 0,
/// ...]`, for [`WebHandle::job_head`], [`WebHandle::job_part`] and [`WebHandle::job_done`].
/// Throws what is wrong (the file, the clip on this body, the keypoints), in the editor's
/// words.
#[wasm_bindgen]
pub fn run_job(job: Vec<u8>, progress: &js_sys::Function) -> Result<js_sys::Array, String> {
    let parts = HostJob::run_for_transfer(&job, &mut |fraction| {
        let _ = progress.call1(&JsValue::NULL, &JsValue::from_f64(fraction));
    })?;
    let out = js_sys::Array::new();
    for part in &parts {
        out.push(&js_sys::Uint8Array::from(part.as_slice()));
    }
    Ok(out)
}

/// A clip arriving from the loading worker, part by part (one task of the page each).
struct ArrivingClip {
    id: u64,
    head: Vec<u8>,
    /// The clip's joints and the body's DOF, to decode the parts with.
    joints: usize,
    dofs: usize,
    parts: Vec<stance_asset::FramesPart>,
    /// What went wrong with a part: the clip is refused with it.
    error: Option<String>,
}

/// Images `indices[i]` of `widths[i] x heights[i]` RGBA8 pixels, one after the other in
/// `rgba`; `None` when the sizes do not add up.
fn decoded_images(
    indices: &[u32],
    widths: &[u32],
    heights: &[u32],
    rgba: &[u8],
) -> Option<Vec<stance_asset::DecodedImage>> {
    if indices.len() != widths.len() || widths.len() != heights.len() {
        return None;
    }
    let sizes = widths.iter().zip(heights).map(|(&width, &height)| {
        (width as usize)
            .checked_mul(height as usize)
            .and_then(|n| n.checked_mul(4))
    });
    let parts = split_by_lengths(rgba, sizes)?;
    Some(
        parts
            .into_iter()
            .zip(indices.iter().zip(widths.iter().zip(heights)))
            .map(
                |(pixels, (&index, (&width, &height)))| stance_asset::DecodedImage {
                    index: index as usize,
                    width,
                    height,
                    rgba8: pixels.to_vec(),
                },
            )
            .collect(),
    )
}

/// The running editor, held by the page.
#[wasm_bindgen]
pub struct WebHandle {
    runner: eframe::WebRunner,
    inbox: RefCell<Option<Sender<HostMessage>>>,
    context: Rc<RefCell<Option<egui::Context>>>,
    /// Actions of the page's accessibility mirror, for the next frame.
    accessibility: PendingActions,
    /// Texture pixels of the avatar the loading worker imported, until its bytes arrive.
    arriving_pixels: RefCell<Vec<Vec<u8>>>,
    /// The clip the loading worker opened, until its last part arrives.
    arriving_clip: RefCell<Option<ArrivingClip>>,
    /// The scene the loading worker lifted (the request's id), until its job is done.
    arriving_lift: RefCell<Option<(u64, stance_document::Scene)>>,
}

#[wasm_bindgen]
impl WebHandle {
    /// Installs the panic hook and logger; call `start` next.
    #[wasm_bindgen(constructor)]
    #[allow(clippy::new_without_default)]
    pub fn new() -> Self {
        console_error_panic_hook::set_once();
        eframe::WebLogger::init(log::LevelFilter::Info).ok();
        Self {
            runner: eframe::WebRunner::new(),
            inbox: RefCell::new(None),
            context: Rc::new(RefCell::new(None)),
            accessibility: PendingActions::default(),
            arriving_pixels: RefCell::new(Vec::new()),
            arriving_clip: RefCell::new(None),
            arriving_lift: RefCell::new(None),
        }
    }

    /// Starts the editor on `canvas` with the posture link `link_fragment` (the address's
    /// fragment, may be empty); rejects with a readable reason when no graphics backend can
    /// start.
    #[wasm_bindgen]
    pub async fn start(
        &self,
        canvas: web_sys::HtmlCanvasElement,
        link_fragment: String,
    ) -> Result<(), JsValue> {
        let (sender, receiver) = std::sync::mpsc::channel();
        *self.inbox.borrow_mut() = Some(sender);
        let context = Rc::clone(&self.context);
        let accessibility = self.accessibility.clone();
        self.runner
            .start(
                canvas,
                eframe::WebOptions::default(),
                Box::new(move |creation| {
                    if creation.wgpu_render_state.is_none() {
                        return Err("neither WebGPU nor WebGL2 could start".into());
                    }
                    *context.borrow_mut() = Some(creation.egui_ctx.clone());
                    // egui's AccessKit tree, mirrored as DOM elements by the page.
                    creation.egui_ctx.add_plugin(AccessibilityBridge::new(
                        Box::new(|_, json| {
                            if let Err(error) = host_accessibility(json) {
                                log::warn!("accessibility mirror: {}", describe(&error));
                            }
                        }),
                        accessibility,
                    ));
                    let mut app =
                        StanceApp::new(creation, Box::new(PageHooks))?.with_inbox(receiver);
                    app.open_startup(Some(&link_fragment));
                    Ok(Box::new(app))
                }),
            )
            .await
    }

    /// Hands `message` to the editor between frames (after the messages queued before it)
    /// and asks for a frame only where the editor has something to show: not while the
    /// loading worker imports the avatar it opened or the page steps its upload (frames that
    /// repaint a software-composited canvas are slow). Queued for the next frame where the
    /// editor cannot be reached now.
    fn deliver_now(&self, message: HostMessage) {
        if let Some(mut app) = self.runner.app_mut::<StanceApp>() {
            let can_wait = app.receive_between_frames(message);
            drop(app);
            if !can_wait {
                self.request_frame();
            }
        } else {
            self.send(message);
        }
    }

    /// Queues `message` for the editor's next frame, and asks for that frame.
    fn send(&self, message: HostMessage) {
        if let Some(sender) = self.inbox.borrow().as_ref() {
            let _ = sender.send(message);
        }
        self.request_frame();
    }

    fn request_frame(&self) {
        if let Some(context) = self.context.borrow().as_ref() {
            context.request_repaint();
        }
    }

    /// Opens a posture link (the address's fragment changed).
    #[wasm_bindgen]
    pub fn open_link(&self, fragment: String) {
        self.send(HostMessage::OpenLink(fragment));
    }

    /// Opens a file the user picked or dropped.
    #[wasm_bindgen]
    pub fn open_file(&self, name: String, bytes: Vec<u8>) {
        self.deliver_now(HostMessage::OpenFile { name, bytes });
    }

    /// Opens files picked or dropped together (a `.gltf` with its `.bin` and images, a
    /// folder): `names[i]` (with its path in a dropped folder) holds `lengths[i]` bytes of
    /// `bytes`, one after the other. Lengths that do not add up are reported, not opened.
    #[wasm_bindgen]
    pub fn open_files(&self, names: Vec<String>, lengths: Vec<u32>, bytes: Vec<u8>) {
        let parts = split_by_lengths(&bytes, lengths.iter().map(|&n| Some(n as usize)));
        let Some(parts) = parts.filter(|parts| parts.len() == names.len()) else {
            self.send(HostMessage::Failed(
                "the dropped files could not be read together".to_owned(),
            ));
            return;
        };
        let files = names
            .into_iter()
            .zip(parts)
            .map(|(name, part)| (name, part.to_vec()))
            .collect();
        self.deliver_now(HostMessage::OpenFiles(files));
    }

    /// The texture images of the avatar file `file` (as named to `open_file`/`open_files`),
    /// decoded by the browser: image `indices[i]` is `widths[i] x heights[i]` RGBA8 pixels,
    /// one after the other in `rgba`. Sent before the file itself; its import takes them as
    /// they are. Sizes that do not add up send nothing (the import decodes the images).
    #[wasm_bindgen]
    pub fn decoded_images(
        &self,
        file: String,
        indices: Vec<u32>,
        widths: Vec<u32>,
        heights: Vec<u32>,
        rgba: Vec<u8>,
    ) {
        let Some(images) = decoded_images(&indices, &widths, &heights, &rgba) else {
            return;
        };
        self.send(HostMessage::DecodedImages { file, images });
    }

    /// An action of the page's accessibility mirror (`web/accessibility.js`) on the widget
    /// with node id `id`: `click`, `focus`, `increment`, `decrement`, `set_number` or
    /// `set_text` (with `value`). False when the action or its value is not understood.
    #[wasm_bindgen]
    pub fn accessibility_action(&self, id: String, action: String, value: Option<String>) -> bool {
        let Some(action) = PageAction::parse(&action, value.as_deref()) else {
            return false;
        };
        let queued = self.accessibility.push(&id, action);
        self.request_frame();
        queued
    }

    /// The pixels of the next texture of the avatar the loading worker imported
    /// ([`import_avatar_file`]), given one call (one task of the page) each before
    /// [`WebHandle::avatar_imported`].
    #[wasm_bindgen]
    pub fn avatar_texture(&self, pixels: Vec<u8>) {
        self.arriving_pixels.borrow_mut().push(pixels);
    }

    /// The avatar file `name` the editor asked the page to import (`stanceHost.importAvatar`),
    /// as the loading worker returned it ([`import_avatar_file`]: `bytes`, its textures'
    /// pixels given before), imported in `import_ms` with `images_from_host` textures
    /// decoded by the browser.
    #[wasm_bindgen]
    pub fn avatar_imported(
        &self,
        name: String,
        bytes: Vec<u8>,
        import_ms: f64,
        images_from_host: u32,
    ) {
        let started = web_time::Instant::now();
        let transfer = stance_asset::AvatarTransfer {
            avatar: bytes,
            pixels: std::mem::take(&mut *self.arriving_pixels.borrow_mut()),
        };
        let result = transfer
            .into_avatar()
            .map(|avatar| {
                Box::new(ImportedAvatar {
                    avatar,
                    import_ms,
                    in_worker: true,
                    transfer_ms: started.elapsed().as_secs_f64() * 1e3,
                    images_from_host: images_from_host as usize,
                })
            })
            .map_err(|error| error.to_string());
        // Taken now rather than at the next frame: the avatar's upload starts in the page's
        // tasks, and the first frame after it draws the avatar instead of its capsules.
        self.deliver_now(HostMessage::AvatarImported { name, result });
    }

    /// A share of the avatar's GPU upload, stepped by the page in a task of its own when the
    /// editor asked it (`stanceHost.uploadAvatar`): true while more is left. The last share
    /// asks for the frame that draws the avatar.
    #[wasm_bindgen]
    pub fn upload_avatar_step(&self) -> bool {
        let more = self
            .runner
            .app_mut::<StanceApp>()
            .is_some_and(|mut app| app.upload_avatar_task());
        if !more {
            self.request_frame();
        }
        more
    }

    /// The avatar file `name` the editor asked the page to import could not be: `reason`
    /// says why (the importer's words).
    #[wasm_bindgen]
    pub fn avatar_import_failed(&self, name: String, reason: String) {
        self.arriving_pixels.borrow_mut().clear();
        self.send(HostMessage::AvatarImported {
            name,
            result: Err(reason),
        });
    }

    /// How far the loading worker has got with the job `id` (0 to 1).
    #[wasm_bindgen]
    pub fn job_progress(&self, id: f64, fraction: f64) {
        self.send(HostMessage::JobProgress {
            id: id as u64,
            fraction,
        });
    }

    /// The head of the result of the job `id` ([`run_job`]): a lifted scene whole, or the
    /// head of a clip whose parts follow ([`WebHandle::job_part`]), one task each.
    #[wasm_bindgen]
    pub fn job_head(&self, id: f64, head: Vec<u8>) {
        let head = match stance_editor::JobHead::from_bytes(&head) {
            Ok(stance_editor::JobHead::Clip(head)) => head,
            Ok(stance_editor::JobHead::Lift(scene)) => {
                *self.arriving_lift.borrow_mut() = Some((id as u64, scene));
                return;
            }
            Err(error) => {
                self.job_failed(id, format!("The result could not be handed over: {error}."));
                return;
            }
        };
        let dofs = self
            .runner
            .app_mut::<StanceApp>()
            .map(|app| app.model().session().skeleton().dof_count());
        let joints = stance_asset::ClipTransfer::head_joints(&head);
        let error = match (&joints, dofs) {
            (Err(error), _) => Some(error.to_string()),
            (_, None) => Some("the editor was busy".to_owned()),
            _ => None,
        };
        *self.arriving_clip.borrow_mut() = Some(ArrivingClip {
            id: id as u64,
            head,
            joints: joints.unwrap_or(0),
            dofs: dofs.unwrap_or(0),
            parts: Vec::new(),
            error,
        });
    }

    /// The next part of frames of the clip request `id`, decoded now (a task of the page).
    #[wasm_bindgen]
    pub fn job_part(&self, id: f64, part: Vec<u8>) {
        let mut arriving = self.arriving_clip.borrow_mut();
        let Some(clip) = arriving.as_mut().filter(|clip| clip.id == id as u64) else {
            return;
        };
        if clip.error.is_some() {
            return;
        }
        match stance_asset::ClipTransfer::decode_part(&part, clip.joints, clip.dofs) {
            Ok(part) => clip.parts.push(part),
            Err(error) => clip.error = Some(error.to_string()),
        }
    }

    /// The job `id` has all its parts: the lifted scene or the clip goes to the editor.
    #[wasm_bindgen]
    pub fn job_done(&self, id: f64) {
        let lifted = self.arriving_lift.borrow_mut().take();
        if let Some((lift, scene)) = lifted
            && lift == id as u64
        {
            self.deliver_now(HostMessage::KeypointsLifted {
                id: lift,
                result: Ok(Box::new(scene)),
            });
            return;
        }
        let Some(clip) = self
            .arriving_clip
            .borrow_mut()
            .take()
            .filter(|clip| clip.id == id as u64)
        else {
            return;
        };
        let result = match clip.error {
            Some(error) => Err(error),
            None => stance_asset::ClipTransfer::assemble(&clip.head, clip.parts, clip.dofs)
                .map(Box::new)
                .map_err(|error| error.to_string()),
        }
        .map_err(|error| format!("The clip could not be handed over: {error}."));
        self.deliver_now(HostMessage::ClipOpened {
            id: clip.id,
            result,
        });
    }

    /// The job `id` could not be done: `reason` says why.
    #[wasm_bindgen]
    pub fn job_failed(&self, id: f64, reason: String) {
        let mut arriving = self.arriving_clip.borrow_mut();
        if arriving.as_ref().is_some_and(|clip| clip.id == id as u64) {
            *arriving = None;
        }
        drop(arriving);
        self.arriving_lift
            .borrow_mut()
            .take_if(|(lift, _)| *lift == id as u64);
        self.send(HostMessage::JobFailed {
            id: id as u64,
            reason,
        });
    }

    /// The person the page's pose detector (`web/photo.js`: MediaPipe Pose in a worker) found
    /// in the photo `name` of `width` x `height` pixels: `landmarks` holds MediaPipe's 33
    /// landmarks as `x, y, z, visibility` each (x and y fractions of the photo); `rgba` is the
    /// photo to show behind the viewport, `reference_width` x `reference_height` RGBA8
    /// pixels; `detect_ms` the detection's time. Lifted as keypoints by the editor.
    #[wasm_bindgen]
    #[allow(clippy::too_many_arguments)]
    pub fn photo_detected(
        &self,
        name: String,
        width: u32,
        height: u32,
        landmarks: Vec<f32>,
        rgba: Vec<u8>,
        reference_width: u32,
        reference_height: u32,
        detect_ms: f64,
    ) {
        let landmarks = landmarks
            .chunks_exact(4)
            .map(|l| stance_editor::model::photo::Landmark {
                x: l[0],
                y: l[1],
                z: l[2],
                visibility: l[3],
            })
            .collect();
        let photo = stance_editor::model::photo::DetectedPhoto {
            name,
            size_px: [width, height],
            landmarks,
            reference_rgba: rgba,
            reference_size_px: [reference_width, reference_height],
            detect_ms,
        };
        self.deliver_now(HostMessage::PhotoDetected(Box::new(photo)));
    }

    /// The photo `name` could not be opened (not an image, no person found, no detector):
    /// `reason` says why.
    #[wasm_bindgen]
    pub fn photo_failed(&self, name: String, reason: String) {
        self.send(HostMessage::PhotoFailed { name, reason });
    }

    /// Tells the editor that something the page did for it failed.
    #[wasm_bindgen]
    pub fn report_failure(&self, reason: String) {
        self.send(HostMessage::Failed(reason));
    }

    /// The sensor device is open (`web/sensors.js`).
    #[wasm_bindgen]
    pub fn sensor_connected(&self, device: String) {
        self.send(HostMessage::SensorConnected { device });
    }

    /// Bytes from the serial sensor device.
    #[wasm_bindgen]
    pub fn sensor_bytes(&self, bytes: Vec<u8>) {
        self.send(HostMessage::SensorBytes {
            bytes,
            arrived: web_time::Instant::now(),
        });
    }

    /// One input report from the HID sensor device.
    #[wasm_bindgen]
    pub fn sensor_report(&self, report_id: u8, data: Vec<u8>) {
        self.send(HostMessage::SensorReport {
            report_id,
            data,
            arrived: web_time::Instant::now(),
        });
    }

    /// The sensor device went away or could not be opened.
    #[wasm_bindgen]
    pub fn sensor_lost(&self, reason: String) {
        self.send(HostMessage::SensorLost { reason });
    }

    /// The editor's state as JSON: document, joint positions (world and screen), task
    /// statuses, notice, button rectangles (see `StanceApp::state_json`). Built when asked
    /// (the page's test hook and scripts), never per frame; `"{}"` before the editor runs or
    /// while it is busy.
    #[wasm_bindgen]
    pub fn state_json(&self) -> String {
        self.runner
            .app_mut::<StanceApp>()
            .map_or_else(|| "{}".to_owned(), |app| app.state_json())
    }

    /// Stops the editor and frees its resources.
    #[wasm_bindgen]
    pub fn destroy(&self) {
        self.runner.destroy();
    }

    /// The panic message, if the editor has crashed.
    #[wasm_bindgen]
    pub fn panic_message(&self) -> Option<String> {
        self.runner.panic_summary().map(|summary| summary.message())
    }
}

/// `bytes` cut into consecutive parts of the given lengths; `None` when a length is unknown
/// (overflowed) or the lengths do not add up to `bytes`.
fn split_by_lengths(
    bytes: &[u8],
    lengths: impl Iterator<Item = Option<usize>>,
) -> Option<Vec<&[u8]>> {
    let mut parts = Vec::new();
    let mut at = 0usize;
    for length in lengths {
        let end = at.checked_add(length?)?;
        parts.push(bytes.get(at..end)?);
        at = end;
    }
    (at == bytes.len()).then_some(parts)
}

//! What the user chose for the sensor device (kept in the host's storage), and what the page
//! opens for it: a serial port with the bytes that start and stop the device, or a HID device.

use serde::{Deserialize, Serialize};
use serde_json::json;
use stance_mocap::DecoderConfig;
use stance_mocap::ascii::ComponentOrder;
use stance_mocap::device::DeviceSetup;
use stance_mocap::fob::FobMode;

use super::{DEFAULT_REPLAY_RATE_HZ, DeviceFrame, DeviceKind};
use crate::host::HostHooks;

/// Storage key of the sensor settings (protocol, baud rate... remembered across visits).
pub const SENSOR_SETTINGS_KEY: &str = "stance.sensors.settings";
/// What the user chose for the device; remembered in browser storage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SensorSettings {
    /// The device and its protocol (Flock of Birds, Xsens, SlimeVR...).
    pub device: DeviceKind,
    /// Serial baud rate (ignored for HID devices).
    pub baud_rate: u32,
    /// Flock of Birds record layout.
    pub fob_mode: FobMode,
    /// Flock of Birds group mode (records carry the bird address; needed for several birds).
    pub fob_group: bool,
    /// Number of birds the bridge configures (Flock of Birds).
    pub fob_birds: u8,
    /// Component order of quaternion lines.
    pub ascii_order: ComponentOrder,
    /// How the device's reference frame lies relative to the body.
    pub frame: DeviceFrame,
    /// Samples per sensor per second when replaying a recording.
    pub replay_rate_hz: f64,
}

impl Default for SensorSettings {
    fn default() -> Self {
        let setup = DeviceSetup::default();
        Self {
            device: setup.kind,
            baud_rate: 115_200,
            fob_mode: setup.fob_mode,
            fob_group: setup.fob_group,
            fob_birds: setup.fob_birds,
            ascii_order: setup.ascii_order,
            frame: DeviceFrame::TransmitterZDown,
            replay_rate_hz: DEFAULT_REPLAY_RATE_HZ,
        }
    }
}

impl SensorSettings {
    /// The settings the host kept; unreadable ones are logged and ignored.
    pub fn load(hooks: &dyn HostHooks) -> Option<Self> {
        let text = hooks.load_text(SENSOR_SETTINGS_KEY)?;
        serde_json::from_str(&text)
            .map_err(|error| log::warn!("the saved sensor settings could not be read: {error}"))
            .ok()
    }

    /// Keeps the settings in the host's storage (a failure is logged: they are a convenience).
    pub fn store(&self, hooks: &dyn HostHooks) {
        let Ok(text) = serde_json::to_string(self) else {
            return;
        };
        if let Err(error) = hooks.save_text(SENSOR_SETTINGS_KEY, &text) {
            log::warn!("the sensor settings could not be saved: {error}");
        }
    }

    /// The device with the settings that change how it is started and read.
    pub fn device_setup(&self) -> DeviceSetup {
        DeviceSetup {
            kind: self.device,
            fob_mode: self.fob_mode,
            fob_group: self.fob_group,
            fob_birds: self.fob_birds,
            ascii_order: self.ascii_order,
        }
    }

    /// The decoder configuration for these settings.
    pub fn decoder_config(&self) -> DecoderConfig {
        self.device_setup().decoder_config()
    }

    /// What the page must open: a serial port (with the bytes that set the device up and
    /// start it streaming, and those that stop it before the port closes) or a HID device
    /// among these filters.
    pub fn connection(&self) -> Result<SensorConnection, String> {
        let protocol = self.device.protocol();
        if protocol.is_hid() {
            return Ok(SensorConnection::Hid {
                filters: protocol
                    .hid_filters()
                    .iter()
                    .map(|filter| (filter.vendor_id, filter.product_id))
                    .collect(),
            });
        }
        if self.baud_rate == 0 {
            return Err("the baud rate must be positive".to_owned());
        }
        let setup = self.device_setup();
        Ok(SensorConnection::Serial {
            baud_rate: self.baud_rate,
            setup: setup.start_bytes().map_err(|error| error.to_string())?,
            stop: setup.stop_bytes(),
        })
    }
}

/// What the page opens for the editor.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SensorConnection {
    /// `navigator.serial`: open at this rate, write `setup`, then stream bytes; on
    /// disconnecting, write `stop` before closing the port.
    Serial {
        /// Bits per second.
        baud_rate: u32,
        /// The bytes that set the device up and start its stream.
        setup: Vec<u8>,
        /// The bytes that stop the stream.
        stop: Vec<u8>,
    },
    /// `navigator.hid`: request a device matching one of `(vendor id, product id)`.
    Hid {
        /// The devices offered to the user: USB vendor and product ids.
        filters: Vec<(u16, u16)>,
    },
}

impl SensorConnection {
    /// The request as the page's bridge reads it.
    pub fn to_json(&self) -> String {
        match self {
            SensorConnection::Serial {
                baud_rate,
                setup,
                stop,
            } => json!({"kind": "serial", "baud_rate": baud_rate, "setup": setup, "stop": stop})
                .to_string(),
            SensorConnection::Hid { filters } => json!({
                "kind": "hid",
                "filters": filters
                    .iter()
                    .map(|(vendor, product)| json!({"vendorId": vendor, "productId": product}))
                    .collect::<Vec<_>>(),
            })
            .to_string(),
        }
    }
}

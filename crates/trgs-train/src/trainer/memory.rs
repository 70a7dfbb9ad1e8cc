//! What a training run holds in memory: the GPU buffers of the trainer by what they hold, and the
//! process's peak resident set (the figure `/usr/bin/time -v` reports as its maximum).
use serde::{Deserialize, Serialize};

/// Bytes of GPU buffers a [`crate::trainer::Trainer`] holds, by what they hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GpuMemory {
    /// The Gaussians' attributes and populations.
    pub parameters: u64,
    /// Adam's two moments of every attribute.
    pub moments: u64,
    /// The frame's buffers: layers, projected records, keys, and the backward pass's gradients
    /// (per Gaussian and per view).
    pub frame: u64,
    /// The losses' scratch buffers and the layer gradients.
    pub losses: u64,
    /// The training views' photos on the GPU ([`crate::stages::targets`]).
    pub targets: u64,
}

impl GpuMemory {
    pub fn total(&self) -> u64 {
        self.parameters + self.moments + self.frame + self.losses + self.targets
    }
}

/// The process's peak resident set in bytes (Linux: `VmHWM` of /proc/self/status); None where
/// the system does not say.
pub fn peak_ram_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 =
        line.trim_start_matches("VmHWM:").trim().trim_end_matches("kB").trim().parse().ok()?;
    Some(kib * 1024)
}

/// `bytes` for a progress line: "512 MiB", "3.46 GiB".
pub fn human_bytes(bytes: u64) -> String {
    const MIB: f64 = 1024.0 * 1024.0;
    let mib = bytes as f64 / MIB;
    if mib < 1024.0 { format!("{mib:.0} MiB") } else { format!("{:.2} GiB", mib / 1024.0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peak_ram_is_read_on_linux() {
        if cfg!(target_os = "linux") {
            let bytes = peak_ram_bytes().expect("VmHWM");
            assert!(bytes > 1 << 20, "{bytes}");
        }
    }

    #[test]
    fn bytes_read_as_people_write_them() {
        assert_eq!(human_bytes(512 << 20), "512 MiB");
        assert_eq!(human_bytes(3 << 30), "3.00 GiB");
    }
}

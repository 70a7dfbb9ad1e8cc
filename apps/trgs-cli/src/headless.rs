//! Quiet Vulkan start-up on a machine without a desktop session.
//!
//! Mesa's implicit layer `VK_LAYER_MESA_device_select` looks for the Wayland compositor's GPU
//! whenever an application enables `VK_KHR_wayland_surface`, which wgpu always does on Linux.
//! Without `XDG_RUNTIME_DIR` (a server, a container, CI) libwayland then prints "error:
//! XDG_RUNTIME_DIR is invalid or not set in the environment." twice, and a successful run reads
//! as failing. There is no compositor to find in that case, so the layer has nothing to choose
//! by: the commands restart themselves once with `NODEVICE_SELECT=1`, the Vulkan loader's
//! switch that leaves the layer out. The variable must be in the environment before the loader
//! reads it, and setting it in a running process is `unsafe` (other threads may read the
//! environment), which this workspace forbids: hence `exec`, which replaces the process (same
//! pid, same terminal and signals) before any thread or GPU work starts.
//! `MESA_VK_DEVICE_SELECT` and `DRI_PRIME` (a user choosing a GPU through the layer) keep it.

/// Whether Mesa's device-select layer would print libwayland's error here: no usable
/// `XDG_RUNTIME_DIR`, no `WAYLAND_DISPLAY`, and the layer neither disabled nor asked for.
pub fn device_select_would_complain(var: impl Fn(&str) -> Option<std::ffi::OsString>) -> bool {
    let runtime_dir_usable =
        var("XDG_RUNTIME_DIR").is_some_and(|d| d.to_string_lossy().starts_with('/'));
    !runtime_dir_usable
        && var("WAYLAND_DISPLAY").is_none()
        && var("NODEVICE_SELECT").is_none()
        && var("MESA_VK_DEVICE_SELECT").is_none()
        && var("DRI_PRIME").is_none()
}

/// Restarts this process with `NODEVICE_SELECT=1` where Mesa's device-select layer would print
/// libwayland's error (see the module's comment); otherwise, or if the restart fails, returns
/// and the command runs as it is. Call first thing in `main`.
pub fn quiet_vulkan_layers() {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt as _;
        if !device_select_would_complain(|k| std::env::var_os(k)) {
            return;
        }
        let Ok(exe) = std::env::current_exe() else { return };
        let mut args = std::env::args_os();
        let arg0 = args.next().unwrap_or_else(|| exe.clone().into_os_string());
        // `exec` returns only on failure; the command then runs with the layer's two lines.
        let _failed = std::process::Command::new(&exe)
            .arg0(arg0)
            .args(args)
            .env("NODEVICE_SELECT", "1")
            .exec();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsString;

    fn env<'a>(vars: &'a [(&str, &str)]) -> impl Fn(&str) -> Option<OsString> + 'a {
        move |k| vars.iter().find(|(n, _)| *n == k).map(|(_, v)| OsString::from(v))
    }

    #[test]
    fn only_a_session_without_a_runtime_dir_or_a_choice_restarts() {
        assert!(device_select_would_complain(env(&[])));
        assert!(device_select_would_complain(env(&[("XDG_RUNTIME_DIR", "relative")])));
        assert!(!device_select_would_complain(env(&[("XDG_RUNTIME_DIR", "/run/user/1000")])));
        assert!(!device_select_would_complain(env(&[("WAYLAND_DISPLAY", "/tmp/wl-0")])));
        assert!(!device_select_would_complain(env(&[("NODEVICE_SELECT", "1")])));
        assert!(!device_select_would_complain(env(&[("MESA_VK_DEVICE_SELECT", "10de:2684")])));
        assert!(!device_select_would_complain(env(&[("DRI_PRIME", "1")])));
    }
}

//! Where a shared link's socket lives: one per robot port, in the user's runtime directory.
//!
//! Layer: pure naming plus the directory's checks. The directory is `$XDG_RUNTIME_DIR/station`
//! (the user's own, cleared at logout), else `/tmp/station-UID`; it is made mode 0700 and
//! refused unless it is a real directory owned by the user, so another user can neither read
//! the socket nor put one in its place. The socket's name is the port's canonical path (a pty
//! link like the emulator's `--link /tmp/robot` resolves to its `/dev/pts/N`, so the station
//! holding it and a command naming the link agree), with every byte outside `[A-Za-z0-9._-]`
//! written `%XX`.
//!
//! What can fail: the directory cannot be made or is not safe (`Err` with the reason).

use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// The directory the shared links' sockets live in (not created).
pub fn runtime_dir() -> PathBuf {
    match std::env::var_os("XDG_RUNTIME_DIR") {
        Some(d) if !d.is_empty() => PathBuf::from(d).join("station"),
        _ => PathBuf::from(format!("/tmp/station-{}", uid())),
    }
}

fn uid() -> u32 {
    // The owner of a file the process just made is its effective uid; reading our own
    // /proc entry gives the same without unsafe code.
    std::fs::metadata("/proc/self").map_or(0, |m| m.uid())
}

/// The socket a station holding `port` shares its link on.
pub fn socket_path(port: &Path) -> PathBuf {
    runtime_dir().join(socket_name(port))
}

/// The socket's file name for `port`: its canonical path, escaped.
pub fn socket_name(port: &Path) -> String {
    let canonical = std::fs::canonicalize(port).unwrap_or_else(|_| port.to_path_buf());
    let mut name = String::new();
    for &b in canonical.as_os_str().as_encoded_bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'.' | b'_' | b'-') {
            name.push(char::from(b));
        } else {
            name.push_str(&format!("%{b:02X}"));
        }
    }
    // A Unix socket's path has at most 107 bytes; a longer port path keeps its end, which
    // names the device, and a hash of the whole.
    if name.len() > 60 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        name.hash(&mut h);
        let tail: String = name.chars().skip(name.chars().count() - 40).collect();
        name = format!("{:016x}-{tail}", h.finish());
    }
    name + ".sock"
}

/// Makes the runtime directory (mode 0700) if needed and checks that it is safe: a real
/// directory (not a link), owned by this user, that nobody else can write.
pub fn prepare_dir(dir: &Path) -> Result<(), String> {
    match std::fs::DirBuilder::new()
        .mode(0o700)
        .recursive(true)
        .create(dir)
    {
        Ok(()) => {}
        Err(e) => return Err(format!("cannot make {}: {e}", dir.display())),
    }
    let meta = std::fs::symlink_metadata(dir)
        .map_err(|e| format!("cannot read {}: {e}", dir.display()))?;
    if !meta.is_dir() {
        return Err(format!("{} is not a directory", dir.display()));
    }
    if meta.uid() != uid() {
        return Err(format!(
            "{} belongs to another user (uid {})",
            dir.display(),
            meta.uid()
        ));
    }
    if meta.permissions().mode() & 0o077 != 0 {
        std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o700))
            .map_err(|e| format!("cannot make {} private: {e}", dir.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_escape_the_path_and_stay_short() {
        assert_eq!(
            socket_name(Path::new("/nonexistent/tty USB0")),
            "%2Fnonexistent%2Ftty%20USB0.sock"
        );
        let long = format!("/nonexistent/{}", "d/".repeat(60));
        let name = socket_name(Path::new(&long));
        assert!(name.len() <= 80, "{name}");
        assert_ne!(name, socket_name(Path::new("/nonexistent/other")));
    }

    #[test]
    fn a_link_resolves_to_the_device_it_names() {
        let dir = std::env::temp_dir().join(format!("share-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let target = dir.join("device");
        std::fs::write(&target, b"").expect("file");
        let link = dir.join("robot");
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&target, &link).expect("link");
        assert_eq!(socket_name(&link), socket_name(&target));
        let _ = std::fs::remove_dir_all(&dir);
    }
}

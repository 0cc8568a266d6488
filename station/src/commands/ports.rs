//! `station ports`: the serial ports, and the pseudo-terminals an emulator may be on.

use std::process::ExitCode;

use serde_json::json;

pub fn ports(json: bool) -> anyhow::Result<ExitCode> {
    let serial = serialport::available_ports().unwrap_or_default();
    let mut ptys: Vec<String> = std::fs::read_dir("/dev/pts")
        .map(|d| {
            d.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.chars().all(|c| c.is_ascii_digit()))
                .map(|n| format!("/dev/pts/{n}"))
                .collect()
        })
        .unwrap_or_default();
    ptys.sort_by_key(|p| p.rsplit('/').next().and_then(|n| n.parse::<u32>().ok()));
    let describe = |t: &serialport::SerialPortType| match t {
        serialport::SerialPortType::UsbPort(u) => format!(
            "USB {:04x}:{:04x} {} {}",
            u.vid,
            u.pid,
            u.manufacturer.as_deref().unwrap_or(""),
            u.product.as_deref().unwrap_or("")
        )
        .trim_end()
        .to_string(),
        serialport::SerialPortType::PciPort => "PCI".into(),
        serialport::SerialPortType::BluetoothPort => "Bluetooth".into(),
        serialport::SerialPortType::Unknown => "serial".into(),
    };
    if json {
        let v = json!({
            "serial": serial.iter().map(|p| json!({
                "path": p.port_name,
                "kind": describe(&p.port_type),
            })).collect::<Vec<_>>(),
            "pty": ptys,
        });
        println!("{}", crate::json_text::pretty(&v)?);
    } else {
        if serial.is_empty() {
            println!("no serial ports found");
        }
        for p in &serial {
            println!("{:<24} {}", p.port_name, describe(&p.port_type));
        }
        if !ptys.is_empty() {
            println!();
            println!("pseudo-terminals (an emulator's port is one of these; it prints which):");
            for p in &ptys {
                println!("  {p}");
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

//! Every WGSL file and define variant is valid for naga, every file under shaders/ is compiled
//! in, and the generated WGSL structs have exactly the Rust layouts (one source of truth).
use trgs_render::layout::all_structs;
use trgs_render::shader::{SOURCES, VARIANTS, compose};

fn validate(name: &str, src: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(src)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(src)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(src)));
    module
}

#[test]
fn every_shader_variant_validates() {
    for (file, defines) in VARIANTS {
        let src = compose(file, defines).unwrap_or_else(|e| panic!("{e}"));
        validate(&format!("{file} {defines:?}"), &src);
    }
}

#[test]
fn no_kernel_binds_more_storage_buffers_than_a_device_is_asked_for() {
    let mut most = 0;
    for (file, defines) in VARIANTS {
        let src = compose(file, defines).unwrap_or_else(|e| panic!("{e}"));
        let module = validate(&format!("{file} {defines:?}"), &src);
        let storage = module
            .global_variables
            .iter()
            .filter(|(_, v)| matches!(v.space, naga::AddressSpace::Storage { .. }))
            .count() as u32;
        assert!(
            storage <= trgs_render::STORAGE_BUFFERS_PER_STAGE,
            "{file} {defines:?} binds {storage} storage buffers, over STORAGE_BUFFERS_PER_STAGE"
        );
        most = most.max(storage);
    }
    // And the constant is what the kernels use, so that no device is refused for nothing.
    assert_eq!(most, trgs_render::STORAGE_BUFFERS_PER_STAGE);
}

#[test]
fn every_wgsl_file_is_compiled_in_and_every_stage_has_a_variant() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    let mut on_disk = Vec::new();
    for sub in ["", "shared/"] {
        for entry in std::fs::read_dir(dir.join(sub)).expect("shaders/ exists") {
            let name = entry.expect("dir entry").file_name().to_string_lossy().into_owned();
            if name.ends_with(".wgsl") {
                on_disk.push(format!("{sub}{name}"));
            }
        }
    }
    for f in &on_disk {
        assert!(SOURCES.iter().any(|(n, _)| n == f), "shaders/{f} is not in shader::SOURCES");
        if !f.starts_with("shared/") {
            assert!(VARIANTS.iter().any(|(n, _)| n == f), "shaders/{f} has no variant to validate");
        }
    }
}

#[test]
fn gpu_struct_layouts_match_rust() {
    let src = trgs_render::layout::prelude();
    let module = validate("prelude", &src);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    for (name, _, offsets, size) in all_structs() {
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("{name} missing from the prelude"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{name} is not a struct")
        };
        assert_eq!(*span as usize, size, "{name}: WGSL size {span} vs Rust {size}");
        assert_eq!(layouter[handle].size as usize, size);
        for (m, (field, off)) in members.iter().zip(&offsets) {
            assert_eq!(m.name.as_deref(), Some(*field));
            assert_eq!(
                m.offset as usize, *off,
                "{name}.{field}: WGSL offset {} vs Rust {off}",
                m.offset
            );
        }
    }
}

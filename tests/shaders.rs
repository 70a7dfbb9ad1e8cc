//! The shader registry across the crates: every WGSL file under shaders/ is compiled in (the
//! build script) and, outside shared/, is the file of a registered kernel; every variant of every
//! registered kernel (its defines on every kind of device) is valid for naga and binds no more
//! storage buffers than a device is asked for; and every GPU struct's WGSL layout is its Rust
//! layout (one source of truth).
use trgs::render::toolkit::layout::StructInfo;
use trgs::render::toolkit::shader::SOURCES;
use trgs::render::toolkit::{BENCH_KERNELS, KernelSpec, RENDER_KERNELS};
use trgs::train::stages::TRAINING_KERNELS;

fn registered() -> Vec<KernelSpec> {
    [RENDER_KERNELS.all(), BENCH_KERNELS.all(), TRAINING_KERNELS.all()].concat()
}

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
fn every_variant_of_every_kernel_validates_within_the_storage_limit() {
    let mut most = 0;
    let mut variants = 0;
    for spec in registered() {
        for defines in spec.variants() {
            let name = format!("{} ({} {defines:?})", spec.name, spec.file);
            let src = spec.source(&defines).unwrap_or_else(|e| panic!("{name}: {e}"));
            let module = validate(&name, &src);
            let storage = module
                .global_variables
                .iter()
                .filter(|(_, v)| matches!(v.space, naga::AddressSpace::Storage { .. }))
                .count() as u32;
            assert!(
                storage <= trgs::render::STORAGE_BUFFERS_PER_STAGE,
                "{name} binds {storage} storage buffers, over STORAGE_BUFFERS_PER_STAGE"
            );
            most = most.max(storage);
            variants += 1;
        }
    }
    // And the constant is what the kernels use, so that no device is refused for nothing.
    assert_eq!(most, trgs::render::STORAGE_BUFFERS_PER_STAGE);
    assert!(variants > 60, "{variants} variants");
}

#[test]
fn every_wgsl_file_is_compiled_in_and_every_stage_is_registered() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut on_disk = Vec::new();
    for group in std::fs::read_dir(&root).expect("shaders/ exists") {
        let group = group.expect("dir entry").file_name().to_string_lossy().into_owned();
        for entry in std::fs::read_dir(root.join(&group)).expect("a shader folder") {
            let name = entry.expect("dir entry").file_name().to_string_lossy().into_owned();
            if name.ends_with(".wgsl") {
                on_disk.push(format!("{group}/{name}"));
            }
        }
    }
    on_disk.sort();
    let compiled: Vec<&str> = SOURCES.iter().map(|(n, _)| *n).collect();
    assert_eq!(on_disk, compiled, "the build script compiles in exactly the files on disk");
    let specs = registered();
    for f in on_disk.iter().filter(|f| !f.starts_with("shared/")) {
        assert!(specs.iter().any(|s| s.file == f), "shaders/{f} has no registered kernel");
    }
    for s in &specs {
        assert!(on_disk.iter().any(|f| f == s.file), "{}: no file shaders/{}", s.name, s.file);
        let same_name = specs.iter().filter(|o| o.name == s.name).count();
        assert_eq!(same_name, 1, "kernel name {} is registered twice", s.name);
    }
}

/// Each struct's size and field offsets in naga's layout of `prelude` against Rust's.
fn check_layouts(prelude: &str, structs: &[StructInfo]) {
    let module = validate("prelude", prelude);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    for (name, _, offsets, size) in structs {
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(*name))
            .unwrap_or_else(|| panic!("{name} missing from the prelude"));
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("{name} is not a struct")
        };
        assert_eq!(*span as usize, *size, "{name}: WGSL size {span} vs Rust {size}");
        assert_eq!(layouter[handle].size as usize, *size);
        assert_eq!(members.len(), offsets.len(), "{name}: field count");
        for (m, (field, off)) in members.iter().zip(offsets) {
            assert_eq!(m.name.as_deref(), Some(*field));
            assert_eq!(m.offset as usize, *off, "{name}.{field}: WGSL offset {} vs Rust", m.offset);
        }
    }
}

#[test]
fn gpu_struct_layouts_match_rust() {
    use trgs::render::toolkit::layout as render;
    use trgs::train::stages::layout as train;
    check_layouts(&render::prelude(), &render::all_structs());
    check_layouts(&train::prelude(), &train::all_structs());
}

//! The open dialog: a small file browser drawn with egui (no native dialog library, so the
//! viewer needs no GTK or portal). Folders, .ply, .glb and .spz files are listed; a folder can
//! be opened as a run folder.
use eframe::egui;
use std::path::{Path, PathBuf};

#[derive(Debug)]
pub struct Browser {
    pub open: bool,
    dir: PathBuf,
    typed: String,
    entries: Vec<(String, bool)>,
    error: Option<String>,
}

/// Files the viewer can open.
pub fn is_model_file(p: &Path) -> bool {
    p.extension().is_some_and(|e| ["ply", "glb", "spz"].iter().any(|m| e.eq_ignore_ascii_case(m)))
}

impl Browser {
    pub fn new(dir: PathBuf) -> Self {
        let mut b = Self {
            open: false,
            typed: dir.display().to_string(),
            dir,
            entries: Vec::new(),
            error: None,
        };
        b.refresh();
        b
    }

    fn refresh(&mut self) {
        self.entries.clear();
        match std::fs::read_dir(&self.dir) {
            Ok(rd) => {
                self.error = None;
                for e in rd.flatten() {
                    let p = e.path();
                    let is_dir = p.is_dir();
                    let hidden = e.file_name().to_string_lossy().starts_with('.');
                    if !hidden && (is_dir || is_model_file(&p)) {
                        self.entries.push((e.file_name().to_string_lossy().into_owned(), is_dir));
                    }
                }
                self.entries.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
            }
            Err(e) => self.error = Some(format!("{}: {e}", self.dir.display())),
        }
    }

    fn go(&mut self, dir: PathBuf) {
        self.dir = dir;
        self.typed = self.dir.display().to_string();
        self.refresh();
    }

    /// Draw the window; returns the path chosen to open.
    pub fn show(&mut self, ctx: &egui::Context) -> Option<PathBuf> {
        let mut chosen = None;
        let mut open = self.open;
        egui::Window::new("Open a model").open(&mut open).default_width(420.0).show(ctx, |ui| {
            ui.horizontal(|ui| {
                let edit = ui.text_edit_singleline(&mut self.typed);
                if edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
                    let p = PathBuf::from(&self.typed);
                    if p.is_dir() {
                        self.go(p);
                    } else {
                        chosen = Some(p);
                    }
                }
                if ui.button("Up").clicked()
                    && let Some(up) = self.dir.parent()
                {
                    self.go(up.to_path_buf());
                }
            });
            if ui.button("Open this folder as a run").clicked() {
                chosen = Some(self.dir.clone());
            }
            if let Some(e) = &self.error {
                ui.colored_label(egui::Color32::LIGHT_RED, e);
            }
            ui.separator();
            egui::ScrollArea::vertical().max_height(360.0).show(ui, |ui| {
                let mut go_to = None;
                for (name, is_dir) in &self.entries {
                    let label = if *is_dir { format!("[{name}]") } else { name.clone() };
                    if ui.selectable_label(false, label).clicked() {
                        let p = self.dir.join(name);
                        if *is_dir {
                            go_to = Some(p);
                        } else {
                            chosen = Some(p);
                        }
                    }
                }
                if let Some(d) = go_to {
                    self.go(d);
                }
            });
        });
        self.open = open && chosen.is_none();
        chosen
    }
}

//! `eval` decodes only the views it measures (`TrainingData::load` with `LoadOptions::evaluate`): the test
//! views, the training views or all of them, each as a training load gives it, and for a scene
//! without test views its first four training views, as training evaluates on.
use std::sync::atomic::{AtomicUsize, Ordering};
use trgs_core::io::{SceneFolder, Split};
use trgs_synthetic::{SyntheticConfig, generate, write_dataset};
use trgs_train::{LoadOptions, Resolution, TrainingData, View};

fn names<'a>(views: impl IntoIterator<Item = &'a View>) -> Vec<String> {
    views.into_iter().map(|v| v.camera.name.clone()).collect()
}

/// The views `split` loads for evaluation, and how many photos were decoded to load them.
fn evaluation(folder: &SceneFolder, split: Split) -> (TrainingData, usize) {
    let decoded = AtomicUsize::new(0);
    let count = |_: usize, _: usize| {
        decoded.fetch_add(1, Ordering::Relaxed);
    };
    let options = LoadOptions {
        resolution: Resolution::Original,
        evaluate: Some(split),
        progress: Some(&count),
    };
    let data = TrainingData::load(folder, &options).expect("load for evaluation");
    (data, decoded.into_inner())
}

#[test]
fn evaluation_decodes_only_the_views_it_measures() {
    let dir = trgs_core::scratch::ScratchDir::new("evaluation-views");
    write_dataset(&generate(&SyntheticConfig::small()), &dir).expect("write the dataset");
    let folder = SceneFolder::open(&dir).expect("open the dataset");
    let whole = TrainingData::load(&folder, &LoadOptions::at(Resolution::Original))
        .expect("load for training");
    assert!(!whole.test.is_empty() && whole.train.len() > whole.test.len());
    for split in [Split::Test, Split::Train, Split::All] {
        let mut expected: Vec<&View> = match split {
            Split::Test => whole.test.iter().collect(),
            Split::Train => whole.train.iter().collect(),
            Split::All => whole.train.iter().chain(&whole.test).collect(),
        };
        if split == Split::All {
            expected.sort_by(|a, b| a.camera.name.cmp(&b.camera.name));
        }
        let (data, decoded) = evaluation(&folder, split);
        assert_eq!(decoded, expected.len(), "{split:?}: only the measured photos are decoded");
        assert_eq!(names(data.eval_views()), names(expected.iter().copied()), "{split:?}");
        for (got, want) in data.eval_views().iter().zip(&expected) {
            assert!(got.image == want.image && got.mask == want.mask, "{}", got.camera.name);
        }
        assert_eq!(
            (data.extent, data.centre, data.size()),
            (whole.extent, whole.centre, whole.size())
        );
        assert_eq!(data.eval_views_name(), "test");
    }
    // No test views: the first four training views stand in, and the report says so.
    std::fs::write(dir.join("test_views.txt"), "").expect("an empty split");
    let folder = SceneFolder::open(&dir).expect("open the dataset");
    let whole = TrainingData::load(&folder, &LoadOptions::at(Resolution::Original))
        .expect("load for training");
    let (data, decoded) = evaluation(&folder, Split::Test);
    assert_eq!(decoded, 4);
    assert_eq!(names(data.eval_views()), names(&whole.train[..4]));
    assert_eq!(names(data.eval_views()), names(whole.eval_views()));
    assert_eq!(data.eval_views_name(), whole.eval_views_name());
    assert!(data.eval_views_name().starts_with("training"));
}

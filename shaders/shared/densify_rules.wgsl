// The rules of classic densification that more than one `densify_plan` kernel applies (twin:
// trgs_train::densify::classic::decide::Rules, which compares the same f32 values the same way).
// The including kernel declares `params: DensifyPlanParams`, `stats` (densify_stats' records) and
// `opacity_logits`. The thresholds come as logits and log scales, so that no kernel rounds an exp
// or a sigmoid that its twin would round differently.

fn is_transparent(i: u32) -> bool {
    return opacity_logits[i] < params.transparent_logit;
}

// Seen at least once, not transparent, and an average screen-space gradient at the threshold:
// sum >= threshold * observations (a product, which both sides round alike; a quotient may not).
fn is_candidate(i: u32) -> bool {
    let s = stats[i];
    return s.y > 0.0 && !is_transparent(i) && s.x >= params.grad_threshold * s.y;
}

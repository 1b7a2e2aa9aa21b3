//! Dilation: empty texels next to filled ones take the mean of their filled neighbours, pass
//! after pass, so a chart's values run out into its padding and over the texels left out under
//! geometry. Bilinear filtering (and mipmapping) at a chart's edge then blends the chart with
//! itself, not with black.

/// Fills, in `passes` passes, each empty texel of a `w × h` page that has a filled 8-neighbour
/// with the mean of those neighbours (as they were before the pass); `filled` is updated.
pub fn dilate(page: &mut [[f32; 3]], filled: &mut [bool], w: usize, h: usize, passes: usize) {
    for _ in 0..passes {
        let mut grown = Vec::new();
        for y in 0..h {
            for x in 0..w {
                if filled[y * w + x] {
                    continue;
                }
                let (mut sum, mut n) = ([0.0f32; 3], 0u32);
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                        if (dx, dy) == (0, 0)
                            || nx < 0
                            || ny < 0
                            || nx >= w as i64
                            || ny >= h as i64
                        {
                            continue;
                        }
                        let j = ny as usize * w + nx as usize;
                        if filled[j] {
                            for k in 0..3 {
                                sum[k] += page[j][k];
                            }
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    grown.push((y * w + x, sum.map(|s| s / n as f32)));
                }
            }
        }
        if grown.is_empty() {
            break;
        }
        for (i, v) in grown {
            page[i] = v;
            filled[i] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_run_out_as_far_as_the_passes_go() {
        let (w, h) = (5, 1);
        let mut page = vec![[0.0; 3]; w * h];
        let mut filled = vec![false; w * h];
        page[0] = [2.0, 2.0, 2.0];
        filled[0] = true;
        dilate(&mut page, &mut filled, w, h, 2);
        assert_eq!(filled, [true, true, true, false, false]);
        assert_eq!(page[2], [2.0; 3]);
        assert_eq!(page[3], [0.0; 3]);
    }
}

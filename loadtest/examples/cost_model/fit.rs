//! The least-squares fit of a cost model to measured times.

/// Non-negative least squares (Lawson–Hanson): `x ≥ 0` minimising
/// `|A x − y|²`, `a` row-major with `m` columns.
pub fn nnls(a: &[Vec<f64>], y: &[f64], m: usize) -> Vec<f64> {
    // Columns scaled to unit norm for conditioning.
    let norms: Vec<f64> = (0..m)
        .map(|j| a.iter().map(|r| r[j] * r[j]).sum::<f64>().sqrt())
        .collect();
    let col = |i: usize, j: usize| {
        if norms[j] > 0.0 {
            a[i][j] / norms[j]
        } else {
            0.0
        }
    };
    let rows = a.len();
    let mut x = vec![0.0; m];
    let mut passive = vec![false; m];
    let residual = |x: &[f64]| -> Vec<f64> {
        (0..rows)
            .map(|i| y[i] - (0..m).map(|j| col(i, j) * x[j]).sum::<f64>())
            .collect()
    };
    // Least squares on the passive set (normal equations).
    let solve = |passive: &[bool]| -> Vec<f64> {
        let idx: Vec<usize> = (0..m).filter(|&j| passive[j]).collect();
        let k = idx.len();
        let mut g = vec![vec![0.0; k + 1]; k];
        for (p, &jp) in idx.iter().enumerate() {
            for (q, &jq) in idx.iter().enumerate() {
                g[p][q] = (0..rows).map(|i| col(i, jp) * col(i, jq)).sum();
            }
            g[p][k] = (0..rows).map(|i| col(i, jp) * y[i]).sum();
            g[p][p] += 1e-12;
        }
        for p in 0..k {
            let piv = (p..k)
                .max_by(|&u, &v| g[u][p].abs().total_cmp(&g[v][p].abs()))
                .unwrap();
            g.swap(p, piv);
            let pivot = g[p].clone();
            for (r, row) in g.iter_mut().enumerate() {
                if r != p && pivot[p] != 0.0 {
                    let f = row[p] / pivot[p];
                    for (x, y) in row[p..].iter_mut().zip(&pivot[p..]) {
                        *x -= f * y;
                    }
                }
            }
        }
        let mut z = vec![0.0; m];
        for (p, &j) in idx.iter().enumerate() {
            z[j] = if g[p][p] != 0.0 {
                g[p][k] / g[p][p]
            } else {
                0.0
            };
        }
        z
    };
    for _ in 0..3 * m {
        let r = residual(&x);
        let w: Vec<f64> = (0..m)
            .map(|j| (0..rows).map(|i| col(i, j) * r[i]).sum())
            .collect();
        let Some(j) = (0..m)
            .filter(|&j| !passive[j] && w[j] > 1e-10)
            .max_by(|&u, &v| w[u].total_cmp(&w[v]))
        else {
            break;
        };
        passive[j] = true;
        loop {
            let z = solve(&passive);
            if (0..m).all(|j| !passive[j] || z[j] > 0.0) {
                x = z;
                break;
            }
            let alpha = (0..m)
                .filter(|&j| passive[j] && z[j] <= 0.0)
                .map(|j| x[j] / (x[j] - z[j]))
                .fold(f64::INFINITY, f64::min);
            for j in 0..m {
                x[j] += alpha * (z[j] - x[j]);
                if passive[j] && x[j] <= 1e-15 {
                    passive[j] = false;
                    x[j] = 0.0;
                }
            }
        }
    }
    (0..m)
        .map(|j| if norms[j] > 0.0 { x[j] / norms[j] } else { 0.0 })
        .collect()
}

/// Coefficients fitted on relative error (rows `terms/measured` against
/// 1), then refitted a few times with the rows predicted low weighted
/// `UNDER` times more: a prediction a little high is better than one low.
pub fn fit(rows: &[(Vec<f64>, f64)], m: usize) -> Vec<f64> {
    const UNDER: f64 = 2.0;
    let mut weights = vec![1.0; rows.len()];
    let mut coef = Vec::new();
    for _ in 0..6 {
        let a: Vec<Vec<f64>> = rows
            .iter()
            .zip(&weights)
            .map(|((t, y), w)| t.iter().map(|v| w * v / y).collect())
            .collect();
        coef = nnls(&a, &weights, m);
        for ((t, y), w) in rows.iter().zip(weights.iter_mut()) {
            let pred: f64 = t.iter().zip(&coef).map(|(a, b)| a * b).sum();
            *w = if pred < *y { UNDER } else { 1.0 };
        }
    }
    coef
}

pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

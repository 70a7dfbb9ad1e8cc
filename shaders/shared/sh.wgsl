// Real spherical harmonics up to degree 3 with the INRIA 3DGS constants and signs (twin:
// trgs_core::sh): the basis at a unit direction and its derivatives. Entries above `degree` are
// zero.

fn sh_basis(degree: u32, d: vec3<f32>) -> array<f32, 16> {
    var b: array<f32, 16>;
    b[0] = SH_C0;
    if degree >= 1u {
        let x = d.x;
        let y = d.y;
        let z = d.z;
        b[1] = -SH_C1 * y;
        b[2] = SH_C1 * z;
        b[3] = -SH_C1 * x;
        if degree >= 2u {
            let xx = x * x;
            let yy = y * y;
            let zz = z * z;
            b[4] = SH_C2_0 * x * y;
            b[5] = SH_C2_1 * y * z;
            b[6] = SH_C2_2 * (2.0 * zz - xx - yy);
            b[7] = SH_C2_3 * x * z;
            b[8] = SH_C2_4 * (xx - yy);
            if degree >= 3u {
                b[9] = SH_C3_0 * y * (3.0 * xx - yy);
                b[10] = SH_C3_1 * x * y * z;
                b[11] = SH_C3_2 * y * (4.0 * zz - xx - yy);
                b[12] = SH_C3_3 * z * (2.0 * zz - 3.0 * xx - 3.0 * yy);
                b[13] = SH_C3_4 * x * (4.0 * zz - xx - yy);
                b[14] = SH_C3_5 * z * (xx - yy);
                b[15] = SH_C3_6 * x * (xx - 3.0 * yy);
            }
        }
    }
    return b;
}

// d(basis_k)/d(x, y, z).
fn sh_basis_grad(degree: u32, d: vec3<f32>) -> array<vec3<f32>, 16> {
    var g: array<vec3<f32>, 16>;
    if degree >= 1u {
        let x = d.x;
        let y = d.y;
        let z = d.z;
        g[1] = vec3<f32>(0.0, -SH_C1, 0.0);
        g[2] = vec3<f32>(0.0, 0.0, SH_C1);
        g[3] = vec3<f32>(-SH_C1, 0.0, 0.0);
        if degree >= 2u {
            g[4] = vec3<f32>(SH_C2_0 * y, SH_C2_0 * x, 0.0);
            g[5] = vec3<f32>(0.0, SH_C2_1 * z, SH_C2_1 * y);
            g[6] = vec3<f32>(-2.0 * SH_C2_2 * x, -2.0 * SH_C2_2 * y, 4.0 * SH_C2_2 * z);
            g[7] = vec3<f32>(SH_C2_3 * z, 0.0, SH_C2_3 * x);
            g[8] = vec3<f32>(2.0 * SH_C2_4 * x, -2.0 * SH_C2_4 * y, 0.0);
            if degree >= 3u {
                let xx = x * x;
                let yy = y * y;
                let zz = z * z;
                g[9] = vec3<f32>(SH_C3_0 * 6.0 * x * y, SH_C3_0 * (3.0 * xx - 3.0 * yy), 0.0);
                g[10] = vec3<f32>(SH_C3_1 * y * z, SH_C3_1 * x * z, SH_C3_1 * x * y);
                g[11] = vec3<f32>(-2.0 * SH_C3_2 * x * y, SH_C3_2 * (4.0 * zz - xx - 3.0 * yy), 8.0 * SH_C3_2 * y * z);
                g[12] = vec3<f32>(-6.0 * SH_C3_3 * x * z, -6.0 * SH_C3_3 * y * z, SH_C3_3 * (6.0 * zz - 3.0 * xx - 3.0 * yy));
                g[13] = vec3<f32>(SH_C3_4 * (4.0 * zz - 3.0 * xx - yy), -2.0 * SH_C3_4 * x * y, 8.0 * SH_C3_4 * x * z);
                g[14] = vec3<f32>(2.0 * SH_C3_5 * x * z, -2.0 * SH_C3_5 * y * z, SH_C3_5 * (xx - yy));
                g[15] = vec3<f32>(SH_C3_6 * (3.0 * xx - 3.0 * yy), -6.0 * SH_C3_6 * x * y, 0.0);
            }
        }
    }
    return g;
}

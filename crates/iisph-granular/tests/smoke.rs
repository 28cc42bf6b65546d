mod common;
use iisph_granular::{FluidSolver, IisphParams};

#[test]
fn water_block_settles() {
    let p = IisphParams::<f64>::for_spacing(0.025);
    let (mut solver, mut state) = common::block_solver(p, [10, 10, 10], [20.0, 20.0, 10.0]);
    for f in 0..40 {
        let st = solver.step(&mut state).unwrap();
        eprintln!(
            "{f} it {} unconv {} err {:.2e} max {:.4} mean {:.4} ke {:.3e}",
            st.iterations,
            st.unconverged_substeps,
            st.last_solve_error,
            st.max_density_ratio,
            st.mean_density_ratio,
            st.kinetic_energy
        );
    }
}

use mpsfsi::bench::operators::*;

#[test]
#[ignore]
fn print_convergence_table() {
    let rows = convergence_table();
    println!("{}", convergence_markdown(&rows));
}

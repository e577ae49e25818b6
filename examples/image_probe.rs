//! Prints the samples of an image around a point (debugging aid).
//! cargo run --release --example image_probe -- IMAGE X Y [R] [STEP]
fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let (g, info) = pinsight::vision::image_io::load_path(std::path::Path::new(&a[0])).unwrap();
    let x: i64 = a[1].parse().unwrap();
    let y: i64 = a[2].parse().unwrap();
    let r: i64 = a.get(3).map(|s| s.parse().unwrap()).unwrap_or(12);
    let st: i64 = a.get(4).map(|s| s.parse().unwrap()).unwrap_or(1);
    println!("{info:?}");
    for yy in (y - r..=y + r).step_by(st as usize) {
        let mut line = format!("{yy:5}:");
        for xx in (x - r..=x + r).step_by(st as usize) {
            if xx >= 0 && yy >= 0 && (xx as u32) < g.width && (yy as u32) < g.height {
                line += &format!("{:6.0}", g.get(xx as u32, yy as u32));
            }
        }
        println!("{line}");
    }
}

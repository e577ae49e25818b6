fn main() -> std::process::ExitCode {
    pinsight::cli::main()
}

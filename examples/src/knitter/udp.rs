//! The UDP transport: the same master and boards as threads with their own sockets on
//! 127.0.0.1, in real time, with a seeded loss-and-duplication filter in front of each socket.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use regler_ring_transfer::{Report, link};

use super::Config;
use super::boards::Board;
use super::master::{Host, Jobs};
use super::plant::{pattern, speeds};
use super::summary::{Link, Summary, summarise};

/// A seeded loss-and-duplication filter in front of a socket.
#[derive(Debug)]
struct Filter {
    rng: ChaCha8Rng,
    loss: f64,
    duplicate: f64,
    lost: u64,
    duplicated: u64,
}

impl Filter {
    fn new(seed: u64, config: &Config) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
            loss: config.loss,
            duplicate: config.duplicate,
            lost: 0,
            duplicated: 0,
        }
    }

    /// How many times a received datagram is taken: 0 (lost), 1, or 2 (duplicated).
    fn copies(&mut self) -> usize {
        if self.rng.random_bool(self.loss) {
            self.lost += 1;
            0
        } else if self.rng.random_bool(self.duplicate) {
            self.duplicated += 1;
            2
        } else {
            1
        }
    }
}

/// Drains a non-blocking socket: every datagram waiting, through the filter.
fn drain(
    socket: &std::net::UdpSocket,
    filter: &mut Filter,
    mut take: impl FnMut(&[u8], std::net::SocketAddr),
) {
    let mut buf = [0u8; 512];
    while let Ok((n, from)) = socket.recv_from(&mut buf) {
        for _ in 0..filter.copies() {
            take(&buf[..n], from);
        }
    }
}

/// The same system over real datagrams: the master and every machine run as threads with their
/// own UDP sockets on 127.0.0.1, in real time, with the seeded filter in front of each socket.
/// Machines run the master's default jobs (no keyboard); a refill datagram carries up to 64
/// owed items. Returns the summary and the boards.
///
/// # Errors
/// A socket error or an invalid configuration, as text.
pub fn run_udp(config: &Config) -> Result<(Summary, Vec<Board>), String> {
    use std::net::UdpSocket;
    use std::time::{Duration, Instant};
    config.validate()?;
    let bind = || -> Result<UdpSocket, String> {
        let s =
            UdpSocket::bind("127.0.0.1:0").map_err(|e| format!("cannot bind 127.0.0.1: {e}"))?;
        s.set_nonblocking(true).map_err(|e| e.to_string())?;
        Ok(s)
    };
    let boards: Vec<Board> = speeds(config)
        .into_iter()
        .enumerate()
        .map(|(i, rpm)| Board::new(i, rpm, config))
        .collect::<Result<_, _>>()?;
    let t0s: Vec<u64> = boards.iter().map(|b| b.t0_ns).collect();
    let mut host = Host::new(config, &t0s)?;
    // A datagram is the link's unit: a refill carries as many owed items as fit (a burst of
    // one-item datagrams at the first fill would overrun the sockets' receive buffers).
    host.batch = link::MAX_REFILL as u32;
    let master_socket = bind()?;
    let master_address = master_socket.local_addr().map_err(|e| e.to_string())?;
    let board_sockets: Vec<UdpSocket> = (0..boards.len())
        .map(|_| bind())
        .collect::<Result<_, _>>()?;
    let board_addresses: Vec<std::net::SocketAddr> = board_sockets
        .iter()
        .map(|s| s.local_addr().map_err(|e| e.to_string()))
        .collect::<Result<_, _>>()?;
    let start = Instant::now();
    let run_for = Duration::from_secs_f64(config.seconds);
    let fault = config.master_fault;
    let master_up = move |t: Duration| {
        fault.is_none_or(|(from, len)| !(from..from + len).contains(&t.as_secs_f64()))
    };
    std::thread::scope(|scope| -> Result<(Summary, Vec<Board>), String> {
        let mut handles = Vec::new();
        for (i, (mut board, socket)) in boards.into_iter().zip(board_sockets).enumerate() {
            let config = config.clone();
            handles.push(scope.spawn(move || -> (Board, u64, u64) {
                let mut filter = Filter::new(config.seed.wrapping_add(1 + i as u64), &config);
                let mut jobs = Jobs::new(i as u32, config.job_rows);
                let needles = u64::from(config.needles);
                let mut expected = |k: u64| {
                    let (job, row) = jobs.at(k / needles);
                    pattern(job, row, (k % needles) as u16)
                };
                let send_report = |report: Report| {
                    let mut frame = [0u8; link::REPORT_LEN];
                    if report.encode(&mut frame).is_ok() {
                        let _ = socket.send_to(&frame, master_address);
                    }
                };
                if let Some(hello) = board.announce() {
                    send_report(hello);
                }
                let begin = Duration::from_millis(100);
                let mut done = 0u64;
                while start.elapsed() < run_for {
                    drain(&socket, &mut filter, |bytes, _| board.frame(bytes));
                    let elapsed = start.elapsed();
                    let due = elapsed.saturating_sub(begin).as_nanos() as u64 / board.t0_ns;
                    while done < due {
                        if let Some(report) = board.needle(&mut expected) {
                            send_report(report);
                        }
                        done += 1;
                    }
                    std::thread::sleep(Duration::from_micros(200));
                }
                (board, filter.lost, filter.duplicated)
            }));
        }
        let mut filter = Filter::new(config.seed ^ 0xA5A5, config);
        while start.elapsed() < run_for {
            let now = start.elapsed();
            let now_ns = now.as_nanos() as u64;
            let up = master_up(now);
            let mut replies = Vec::new();
            drain(&master_socket, &mut filter, |bytes, from| {
                if up {
                    if let Some(m) = board_addresses.iter().position(|a| *a == from) {
                        if let Some(keep_alive) = host.report(now_ns, m, bytes) {
                            replies.push((m, keep_alive));
                        }
                    }
                }
            });
            if up {
                while let Some((m, frame, _)) = host.next_frame(now_ns) {
                    replies.push((m, frame));
                }
            }
            for (m, frame) in replies {
                let _ = master_socket.send_to(&frame, board_addresses[m]);
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        let mut boards = Vec::new();
        let (mut lost, mut duplicated) = (filter.lost, filter.duplicated);
        for h in handles {
            let (board, l, d) = h.join().map_err(|_| "a machine thread panicked")?;
            lost += l;
            duplicated += d;
            boards.push(board);
        }
        let summary = summarise(
            config,
            "udp 127.0.0.1",
            &boards,
            &host,
            Link {
                lost,
                duplicated,
                elapsed_ns: u64::try_from(run_for.as_nanos()).unwrap_or(u64::MAX),
                simulated: false,
            },
            Vec::new(),
        );
        Ok((summary, boards))
    })
}

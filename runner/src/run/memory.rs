//! How much memory a scene's render targets may take: what the kernel and the process's memory
//! cgroups still allow.

use std::path::Path;

/// What the kernel can give this process without swapping, in bytes: `MemAvailable` of
/// /proc/meminfo, or less where the process's memory cgroup allows less.
pub(super) fn available_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
    let host = meminfo.as_deref().and_then(|m| meminfo_field(m, "MemAvailable:")).map(|kib| kib * 1024);
    let membership = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    host.into_iter().chain(cgroup_headroom(Path::new("/sys/fs/cgroup"), &membership)).min()
}

fn meminfo_field(text: &str, name: &str) -> Option<u64> {
    text.lines().find(|l| l.starts_with(name))?.split_whitespace().nth(1)?.parse().ok()
}

/// What this process's memory cgroups still allow (a container's limit, which MemAvailable
/// does not show): the least, over the process's cgroup and its ancestors, of the limit less
/// the working set (usage without the inactive page cache the kernel reclaims first, as
/// `docker stats` counts it). `root` is the cgroup mount and `membership` the text of
/// /proc/self/cgroup; cgroup v2 where the mount is unified, else v1's memory controller. None
/// where no level sets a limit.
fn cgroup_headroom(root: &Path, membership: &str) -> Option<u64> {
    let unified = root.join("cgroup.controllers").exists();
    let (base, own, files) = if unified {
        let own = membership.lines().find_map(|l| l.strip_prefix("0::"));
        (root.to_path_buf(), own, ["memory.max", "memory.current", "memory.stat", "inactive_file "])
    } else {
        let own = membership.lines().find_map(|l| {
            let (controllers, path) = l.split_once(':')?.1.split_once(':')?;
            controllers.split(',').any(|c| c == "memory").then_some(path)
        });
        let files = ["memory.limit_in_bytes", "memory.usage_in_bytes", "memory.stat", "total_inactive_file "];
        (root.join("memory"), own, files)
    };
    let [limit_file, usage_file, stat_file, inactive_field] = files;
    let headroom = |dir: &Path| {
        let read = |file: &str| std::fs::read_to_string(dir.join(file)).ok();
        // "max" (v2) does not parse: no limit at this level.
        let limit = read(limit_file)?.trim().parse::<u64>().ok()?;
        let usage = read(usage_file)?.trim().parse::<u64>().ok()?;
        let inactive = read(stat_file)
            .and_then(|stat| {
                stat.lines().find_map(|l| l.strip_prefix(inactive_field)?.trim().parse::<u64>().ok())
            })
            .unwrap_or(0);
        Some(limit.saturating_sub(usage.saturating_sub(inactive)))
    };
    // In a cgroup namespace the own path may not exist under the mount: the mount's root is
    // then the process's cgroup.
    let leaf = own.map(|path| base.join(path.trim_start_matches('/'))).filter(|dir| dir.is_dir());
    let levels = leaf.as_deref().unwrap_or(&base).ancestors().take_while(|dir| dir.starts_with(&base));
    levels.filter_map(headroom).min()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cgroup_limit_caps_the_memory_budget_at_the_tightest_level() {
        let root = std::env::temp_dir().join(format!("aabench-cgroup-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let write = |file: &str, text: &str| {
            let path = root.join(file);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        };
        const GIB: u64 = 1 << 30;

        // v1: the process in /ci/job; the job allows 4 GiB (3 used, 1 of it reclaimable
        // cache), its parent 8 GiB with 7.5 used; the root sets no limit that matters.
        let v1 = "4:memory:/ci/job\n1:cpu:/\n";
        write("memory/memory.limit_in_bytes", "9223372036854771712\n");
        write("memory/memory.usage_in_bytes", "0\n");
        assert_eq!(cgroup_headroom(&root, v1), Some(9223372036854771712), "root level only");
        write("memory/ci/job/memory.limit_in_bytes", &format!("{}\n", 4 * GIB));
        write("memory/ci/job/memory.usage_in_bytes", &format!("{}\n", 3 * GIB));
        write("memory/ci/job/memory.stat", &format!("cache 1\ntotal_inactive_file {GIB}\n"));
        assert_eq!(cgroup_headroom(&root, v1), Some(2 * GIB), "the job's own limit");
        write("memory/ci/memory.limit_in_bytes", &format!("{}\n", 8 * GIB));
        write("memory/ci/memory.usage_in_bytes", &format!("{}\n", 15 * GIB / 2));
        assert_eq!(cgroup_headroom(&root, v1), Some(GIB / 2), "the parent is tighter");
        // Usage over the limit leaves nothing, without wrapping.
        write("memory/ci/memory.usage_in_bytes", &format!("{}\n", 9 * GIB));
        assert_eq!(cgroup_headroom(&root, v1), Some(0));

        // v2 (a unified mount): "max" sets no limit; the process's own level does.
        write("cgroup.controllers", "memory\n");
        let v2 = "0::/user.slice/run\n";
        write("memory.max", "max\n");
        assert_eq!(cgroup_headroom(&root, v2), None, "no level sets a limit");
        write("user.slice/run/memory.max", &format!("{GIB}\n"));
        write("user.slice/run/memory.current", &format!("{}\n", GIB / 2));
        write("user.slice/run/memory.stat", "anon 1\ninactive_file 0\n");
        assert_eq!(cgroup_headroom(&root, v2), Some(GIB / 2));
        // In a cgroup namespace the path is "/" and the mount's root is the process's cgroup.
        assert_eq!(cgroup_headroom(&root, "0::/\n"), None);
        std::fs::remove_dir_all(&root).unwrap();
    }
}

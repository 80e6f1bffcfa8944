//! Buffer layouts (DRM format modifiers) for scanout buffers the GPU
//! renders into: the ones the output's primary plane accepts for
//! XRGB8888 (its `IN_FORMATS` property) that the Vulkan driver can also
//! render into, linear when nothing else fits.

use drm::control::{Device as _, crtc};

use crate::platform::kms::Card;

/// `DRM_FORMAT_MOD_LINEAR`: rows one after another.
pub const LINEAR: u64 = 0;
/// `DRM_FORMAT_MOD_INVALID`: no modifier (the driver's own layout).
pub const INVALID: u64 = 0x00ff_ffff_ffff_ffff;
/// `DRM_FORMAT_XRGB8888` ('XR24').
pub const XRGB8888: u32 = u32::from_le_bytes(*b"XR24");

/// The modifiers an `IN_FORMATS` blob (`struct drm_format_modifier_blob`)
/// lists for `fourcc`, in its order; `None` where the blob is malformed
/// (counts or offsets that point past its end) or not version 1.
#[must_use]
pub fn parse_in_formats(blob: &[u8], fourcc: u32) -> Option<Vec<u64>> {
    let u32_at = |at: usize| -> Option<u32> {
        Some(u32::from_ne_bytes(blob.get(at..at + 4)?.try_into().ok()?))
    };
    let u64_at = |at: usize| -> Option<u64> {
        Some(u64::from_ne_bytes(blob.get(at..at + 8)?.try_into().ok()?))
    };
    if u32_at(0)? != 1 {
        return None;
    }
    let count_formats = u32_at(8)? as usize;
    let formats_offset = u32_at(12)? as usize;
    let count_modifiers = u32_at(16)? as usize;
    let modifiers_offset = u32_at(20)? as usize;
    // Bounded by the blob before anything is read or allocated.
    if formats_offset.checked_add(count_formats.checked_mul(4)?)? > blob.len()
        || modifiers_offset.checked_add(count_modifiers.checked_mul(24)?)? > blob.len()
    {
        return None;
    }
    let index = (0..count_formats).find(|&i| u32_at(formats_offset + 4 * i) == Some(fourcc));
    let Some(index) = index else {
        return Some(Vec::new());
    };
    let mut out = Vec::new();
    for m in 0..count_modifiers {
        let at = modifiers_offset + 24 * m;
        let (formats, offset, modifier) = (u64_at(at)?, u32_at(at + 8)? as usize, u64_at(at + 16)?);
        let applies = index
            .checked_sub(offset)
            .is_some_and(|bit| bit < 64 && formats & (1 << bit) != 0);
        if applies && !out.contains(&modifier) {
            out.push(modifier);
        }
    }
    Some(out)
}

/// The modifiers to ask gbm for: the plane's (`None`: the plane does not
/// say, so linear only) that the renderer can draw into, in the plane's
/// order; linear where none is shared and both take it, or where the plane
/// says nothing. Empty: no layout both accept.
#[must_use]
pub fn choose(plane: Option<&[u64]>, renderable: &[u64]) -> Vec<u64> {
    let Some(plane) = plane else {
        return if renderable.contains(&LINEAR) {
            vec![LINEAR]
        } else {
            Vec::new()
        };
    };
    plane
        .iter()
        .copied()
        .filter(|m| *m != INVALID && renderable.contains(m))
        .collect()
}

/// The modifiers the primary plane of `crtc` accepts for XRGB8888, from its
/// `IN_FORMATS` property; `None` where the driver does not list them (it
/// then takes linear buffers) or the plane cannot be found.
#[must_use]
pub fn primary_plane_modifiers(card: &Card, crtc: crtc::Handle) -> Option<Vec<u64>> {
    // Primary planes are listed only to clients that ask for all planes.
    drm::Device::set_client_capability(card, drm::ClientCapability::UniversalPlanes, true).ok()?;
    let resources = card.resource_handles().ok()?;
    for handle in card.plane_handles().ok()? {
        let Ok(info) = card.get_plane(handle) else {
            continue;
        };
        if !resources
            .filter_crtcs(info.possible_crtcs())
            .contains(&crtc)
        {
            continue;
        }
        // The plane's properties by name, read once: its `type` (1 is
        // primary) and its `IN_FORMATS` blob.
        let Ok(props) = card.get_properties(handle) else {
            continue;
        };
        let named: Vec<(Vec<u8>, u64)> = props
            .iter()
            .filter_map(|(id, value)| {
                let p = card.get_property(*id).ok()?;
                Some((p.name().to_bytes().to_vec(), *value))
            })
            .collect();
        let value = |name: &[u8]| named.iter().find(|(n, _)| n == name).map(|(_, v)| *v);
        if value(b"type") != Some(1) {
            continue;
        }
        let blob = card.get_property_blob(value(b"IN_FORMATS")?).ok()?;
        return parse_in_formats(&blob, XRGB8888);
    }
    None
}

/// A name for a modifier in the journal (`linear`, or its hexadecimal).
#[must_use]
pub fn name(modifier: u64) -> String {
    match modifier {
        LINEAR => "linear".to_owned(),
        INVALID => "none".to_owned(),
        m => format!("{m:#018x}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A version-1 blob listing `formats` and `(mask, offset, modifier)`.
    fn blob(formats: &[u32], modifiers: &[(u64, u32, u64)]) -> Vec<u8> {
        let formats_offset = 24u32;
        let modifiers_offset = formats_offset + 4 * formats.len() as u32;
        let mut b = Vec::new();
        for v in [
            1,
            0,
            formats.len() as u32,
            formats_offset,
            modifiers.len() as u32,
            modifiers_offset,
        ] {
            b.extend_from_slice(&v.to_ne_bytes());
        }
        for f in formats {
            b.extend_from_slice(&f.to_ne_bytes());
        }
        for (mask, offset, modifier) in modifiers {
            b.extend_from_slice(&mask.to_ne_bytes());
            b.extend_from_slice(&offset.to_ne_bytes());
            b.extend_from_slice(&0u32.to_ne_bytes());
            b.extend_from_slice(&modifier.to_ne_bytes());
        }
        b
    }

    const ARGB: u32 = u32::from_le_bytes(*b"AR24");
    const TILED: u64 = 0x0100_0000_0000_0001; // I915_FORMAT_MOD_X_TILED

    #[test]
    fn in_formats_lists_the_modifiers_whose_mask_names_the_format() {
        // XRGB8888 is format 1: linear and X-tiled name it, a third
        // modifier only ARGB8888.
        let b = blob(
            &[ARGB, XRGB8888],
            &[(0b11, 0, LINEAR), (0b10, 0, TILED), (0b01, 0, 7)],
        );
        assert_eq!(parse_in_formats(&b, XRGB8888), Some(vec![LINEAR, TILED]));
        assert_eq!(parse_in_formats(&b, ARGB), Some(vec![LINEAR, 7]));
        assert_eq!(parse_in_formats(&b, 0x1234), Some(vec![]));
    }

    #[test]
    fn in_formats_masks_are_relative_to_their_offset() {
        let mut formats = vec![ARGB; 70];
        formats[66] = XRGB8888;
        // Offset 64: bit 2 is format 66. Offset 0 cannot reach it.
        let b = blob(&formats, &[(0b100, 64, TILED), (u64::MAX, 0, 9)]);
        assert_eq!(parse_in_formats(&b, XRGB8888), Some(vec![TILED]));
    }

    #[test]
    fn a_malformed_blob_is_refused_not_read_past() {
        let b = blob(&[XRGB8888], &[(1, 0, LINEAR)]);
        assert_eq!(parse_in_formats(&b[..b.len() - 1], XRGB8888), None);
        assert_eq!(parse_in_formats(&b[..10], XRGB8888), None);
        let mut huge = b.clone();
        huge[16..20].copy_from_slice(&u32::MAX.to_ne_bytes());
        assert_eq!(parse_in_formats(&huge, XRGB8888), None);
        let mut v2 = b;
        v2[0] = 2;
        assert_eq!(parse_in_formats(&v2, XRGB8888), None);
    }

    #[test]
    fn choose_keeps_the_planes_order_and_falls_back_to_linear() {
        assert_eq!(
            choose(Some(&[TILED, LINEAR, INVALID]), &[LINEAR, TILED]),
            vec![TILED, LINEAR]
        );
        // A renderer that only draws linear (lavapipe).
        assert_eq!(choose(Some(&[TILED, LINEAR]), &[LINEAR]), vec![LINEAR]);
        assert_eq!(choose(None, &[LINEAR]), vec![LINEAR]);
        // Nothing shared: no zero copy.
        assert_eq!(choose(Some(&[TILED]), &[LINEAR]), Vec::<u64>::new());
        assert_eq!(choose(None, &[TILED]), Vec::<u64>::new());
    }
}

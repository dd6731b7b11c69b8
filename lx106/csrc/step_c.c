/* The state update (report section 3.1) in C float, compiled by
 * xtensa-lx106-elf-gcc -O2 against picolibc's sinf/cosf and GCC's own libgcc
 * soft-float (build.rs): what a C firmware with floats would run. A faithful
 * port of the same equations as paperbot::model::step and src/float.rs:
 *   stop:     nothing moves
 *   straight: x += v t cos th, y += v t sin th
 *   turn:     th' = th + w t, x' = x - D (cos th - cos th'), y' = y - D (sin th - sin th')
 *   (the report prints y + D (...); the core uses the rigid-body sign, see
 *   src/model/state.rs)
 * Units: mm, rad, mm/s, rad/s, s. Like the equations (and the fixed-point
 * Angle, which wraps for free), th is not wrapped; a real float firmware
 * would add a wrap to keep precision, which costs more soft-float calls. */
#include <math.h>

struct pose_f { float x, y, th; };   /* same layout as Rust PoseF (repr(C)) */

enum { STOP = 0, STRAIGHT = 1, TURN = 2 };

__attribute__((noinline))
void c_step(struct pose_f *p, int kind, float rate, float dt, float d)
{
    switch (kind) {
    case STRAIGHT: {
        float s = sinf(p->th), c = cosf(p->th);
        float dist = rate * dt;
        p->x += dist * c;
        p->y += dist * s;
        break;
    }
    case TURN: {
        float th1 = p->th + rate * dt;
        float s0 = sinf(p->th), c0 = cosf(p->th);
        float s1 = sinf(th1), c1 = cosf(th1);
        p->x = p->x - d * (c0 - c1);
        p->y = p->y - d * (s0 - s1);
        p->th = th1;
        break;
    }
    default:
        break;
    }
}
